"""``odohil run``: an unattended calibration session on the robot.

Parses the options into a :class:`~odohil.session.run.SessionSpec` and
runs the session lifecycle (odohil/session/run/): pre-flight, open,
run; odohil/cli/session_view.py shows it, with the exit statuses of
odohil/cli/exit_codes.py (0 trusted, 1 error, 2 bad input or session in use,
3 not trusted, 4 stop unconfirmed, 128 + N signal N).
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console

from odohil.cli.options import (
    UNITS_DEFAULT,
    AllowTurnsOption,
    BaudOption,
    ExcludeOption,
    PortOption,
    RunJsonOption,
    TruthSocketOption,
    UnitsOption,
    option,
    robot_option,
    unit_system,
)
from odohil.cli.render import bad_inputs
from odohil.cli.session_view import drive, finish
from odohil.session.results.outcome import parse_exclude
from odohil.session.run import Opened, SessionSpec, default_session_folder

_PLAN_HELP = (
    'Designs and trial counts, e.g. "k=1,l=6,n=30;k=20,l=0.5,n=30" '
    "(k pairs, l metres, n trials, optional variant=turn|reverse), or general paths, e.g. "
    '"path=square:1.0,cw,n=10" (square:SIDE, polygon:N,SIDE, circle:RADIUS,N; cw|ccw).'
)
_ALLOW_FEW_HELP = (
    "Run a plan with fewer trials a design than the planner's minimum (10); "
    "its estimate is then not exported without --force."
)
_MEASURE_HELP = (
    "`fake` (the fake robot's true pose), a trial file (CSV), or "
    "tcp://HOST:PORT (a motion-capture stream, docs/motion-capture.md)."
)


def run(
    port: PortOption = None,
    *,
    robot_file: Annotated[Path, robot_option()],
    plan_text: Annotated[str, typer.Option("--plan", help=_PLAN_HELP)],
    measure: Annotated[str, typer.Option("--measure", help=_MEASURE_HELP)],
    session: Annotated[
        Path | None,
        typer.Option("--session", help="Session folder (default: odohil-session-<time> here)."),
    ] = None,
    truth_socket: TruthSocketOption = None,
    seed: Annotated[
        int, option("--seed", bound="seed", help="Seed of the simulated tape noise (fake).")
    ] = 0,
    baud: BaudOption = None,
    json_out: RunJsonOption = False,
    exclude_text: ExcludeOption = None,
    units_choice: UnitsOption = UNITS_DEFAULT,
    allow_turns: AllowTurnsOption = False,
    allow_few: Annotated[bool, typer.Option("--allow-few-trials", help=_ALLOW_FEW_HELP)] = False,
) -> None:
    """Run a calibration session unattended: n trials, no prompts, journaled.

    Exit 0 when the final estimate is trusted, 3 when it is printed but not.
    """
    console = Console(stderr=True)
    system = unit_system(units_choice)
    folder = session or default_session_folder()

    def say(opened: Opened) -> None:
        console.print(f"session {folder}")
        console.print(f"robot: {opened.prepared.line.describe()}", soft_wrap=True, markup=False)

    with bad_inputs(console):
        exclude = parse_exclude(exclude_text)
    spec = SessionSpec(
        folder, "new", robot_file, plan=plan_text, measure=measure, port=port, baud=baud,
        truth_socket=truth_socket, seed=seed, exclude=exclude, allow_turns=allow_turns,
        allow_few_trials=allow_few,
    )  # fmt: skip
    outcome = drive(console, spec, system, json_out, say)
    finish(outcome, json_out, console, system=system)
