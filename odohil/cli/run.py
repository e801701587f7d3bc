"""``odohil run``: an unattended calibration session on the robot.

Parses the options into a :class:`~odohil.session.lifecycle.SessionSpec` and
runs the session lifecycle (odohil/session/lifecycle/): pre-flight, open,
run; odohil/cli/session_view.py shows it, with the exit statuses of
odohil/cli/exit_codes.py (0 trusted, 1 error, 2 bad input or session in use,
3 not trusted, 4 stop unconfirmed, 128 + N signal N).
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console

from odohil.cli.exclude import EXCLUDE_HELP, parse_exclude
from odohil.cli.options import UNITS_DEFAULT, UnitsOption, bounded, unit_system
from odohil.cli.robot_option import ROBOT_HELP, robot_callback
from odohil.cli.session_view import (
    BaudOption,
    JsonOption,
    PortOption,
    TruthSocketOption,
    default_session_folder,
    finish,
    prepared_or_exit,
    report_run,
    run_with_progress,
    say_opened,
    session_exit_codes,
)
from odohil.cli.session_view import warn_turns as warn_turns
from odohil.session.lifecycle import SessionSpec, open_session, preflight

_PLAN_HELP = (
    'Designs and trial counts, e.g. "k=1,l=6,n=30;k=20,l=0.5,n=30" '
    "(k pairs, l metres, n trials, optional variant=turn|reverse)."
)
ALLOW_FEW_HELP = (
    "Run a plan with fewer trials a design than the planner's minimum (10); "
    "its estimate is then not exported without --force."
)
ALLOW_TURNS_HELP = (
    "Run `turn` designs on a robot whose turns carry error (\\[robot] turns_exact = false); "
    "the estimate is then not trusted."
)


def run(
    port: PortOption = None,
    *,
    robot_file: Annotated[Path, typer.Option("--robot", callback=robot_callback, help=ROBOT_HELP)],
    plan_text: Annotated[str, typer.Option("--plan", help=_PLAN_HELP)],
    measure: Annotated[
        str,
        typer.Option(
            "--measure",
            help="`fake` (the fake robot's true pose), a trial file (CSV), or "
            "tcp://HOST:PORT (a motion-capture stream, docs/motion-capture.md).",
        ),
    ],
    session: Annotated[
        Path | None,
        typer.Option("--session", help="Session folder (default: odohil-session-<time> here)."),
    ] = None,
    truth_socket: TruthSocketOption = None,
    seed: Annotated[
        int,
        typer.Option(
            "--seed", callback=bounded("seed"), help="Seed of the simulated tape noise (fake)."
        ),
    ] = 0,
    baud: BaudOption = None,
    json_out: JsonOption = False,
    exclude_text: Annotated[str | None, typer.Option("--exclude", help=EXCLUDE_HELP)] = None,
    units_choice: UnitsOption = UNITS_DEFAULT,
    allow_turns: Annotated[bool, typer.Option("--allow-turns", help=ALLOW_TURNS_HELP)] = False,
    allow_few: Annotated[bool, typer.Option("--allow-few-trials", help=ALLOW_FEW_HELP)] = False,
) -> None:
    """Run a calibration session unattended: n trials, no prompts, journaled.

    Exit 0 when the final estimate is trusted, 3 when it is printed but not.
    """
    console = Console(stderr=True)
    system = unit_system(units_choice)
    with session_exit_codes(console, json_out):
        spec = SessionSpec(
            session or default_session_folder(), "new", robot_file, plan=plan_text,
            measure=measure, port=port, baud=baud, truth_socket=truth_socket, seed=seed,
            exclude=parse_exclude(exclude_text), allow_turns=allow_turns,
            allow_few_trials=allow_few,
        )  # fmt: skip
        prepared = prepared_or_exit(preflight(spec), console)
        with open_session(prepared, say_opened(console)) as opened:
            console.print(f"session {spec.folder}")
            console.print(f"robot: {prepared.line.describe()}", soft_wrap=True, markup=False)
            outcome = run_with_progress(console, opened, system)
            report_run(console, outcome)
    finish(outcome, json_out, console, system=system)


def register(app: typer.Typer) -> None:
    """Add ``run`` to the ``odohil`` app."""
    app.command("run")(run)
