"""``odohil resume``: continue a session exactly where its journal stops."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console

from odohil.cli.exit_codes import EXIT_BAD_INPUT
from odohil.cli.options import (
    UNITS_DEFAULT,
    BaudOption,
    PortOption,
    RunJsonOption,
    TruthSocketOption,
    UnitsOption,
    unit_system,
)
from odohil.cli.session_view import drive, finish
from odohil.session.run import Opened, SessionSpec
from odohil.session.run.start_pose import (
    HEADING_TOLERANCE_DEG,
    POSITION_TOLERANCE_M,
    StartPose,
    refuse_off_start,
)
from odohil.session.text.run import resuming

_FROM_HERE_HELP = (
    "Go on although the robot is not where the next trial starts "
    f"(beyond {POSITION_TOLERANCE_M:g} m or {HEADING_TOLERANCE_DEG:g} deg); "
    "the trial then starts where the robot stands."
)
_MEASURE_HELP = (
    "`fake`, a trial file (CSV) or tcp://HOST:PORT (motion capture) for the "
    "remaining trials (default: the session's)."
)


def resume(
    session: Annotated[Path, typer.Argument(help="The session folder to continue.")],
    port: PortOption = None,
    truth_socket: TruthSocketOption = None,
    baud: BaudOption = None,
    measure: Annotated[str | None, typer.Option("--measure", help=_MEASURE_HELP)] = None,
    json_out: RunJsonOption = False,
    units_choice: UnitsOption = UNITS_DEFAULT,
    from_here: Annotated[bool, typer.Option("--from-here", help=_FROM_HERE_HELP)] = False,
) -> None:
    """Continue an interrupted session: no trial lost, none counted twice.

    A trial cut off before or during its motion is voided and redone; one whose
    motion finished resumes at its next missing measurement. The session is
    locked before the port is opened: one in use is refused (exit 2). A robot
    that is not where the next trial starts is refused (exit 2) unless --from-here.
    """
    console = Console(stderr=True)
    system = unit_system(units_choice)
    refused: list[StartPose] = []

    def say(opened: Opened) -> None:
        if opened.torn is not None:
            console.print(f"[yellow]warning[/]: {opened.torn.describe()}")
        console.print(resuming(session, opened.state))
        console.print(f"robot: {opened.prepared.line.describe()}", soft_wrap=True, markup=False)

    def start_check(start: StartPose) -> None:
        console.print(f"robot: {start.describe()}")
        if not start.ok and from_here:
            console.print("[yellow]--from-here[/]: the trial starts where it stands")
        elif not start.ok:
            refused.append(start)
            refuse_off_start(start)

    spec = SessionSpec(
        session, "resume", measure=measure, port=port, baud=baud, truth_socket=truth_socket
    )
    outcome = drive(console, spec, system, json_out, say, start_check)
    finish(outcome, json_out, console, system=system, code=EXIT_BAD_INPUT if refused else None)
