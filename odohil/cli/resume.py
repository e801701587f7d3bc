"""``odohil resume``: continue a session exactly where its journal stops."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console

from odohil import units
from odohil.cli.exit_codes import EXIT_BAD_INPUT
from odohil.cli.options import UNITS_DEFAULT, UnitsOption, unit_system
from odohil.cli.session_view import (
    BaudOption,
    JsonOption,
    PortOption,
    TruthSocketOption,
    finish,
    prepared_or_exit,
    report_run,
    run_with_progress,
    say_opened,
    session_exit_codes,
)
from odohil.session.lifecycle import SessionSpec, open_session, preflight
from odohil.session.start_pose import (
    HEADING_TOLERANCE_DEG,
    POSITION_TOLERANCE_M,
    StartPose,
    refuse_off_start,
)


def resume(
    session: Annotated[Path, typer.Argument(help="The session folder to continue.")],
    port: PortOption = None,
    truth_socket: TruthSocketOption = None,
    baud: BaudOption = None,
    measure: Annotated[
        str | None,
        typer.Option(
            "--measure",
            help="`fake`, a trial file (CSV) or tcp://HOST:PORT (motion capture) for the "
            "remaining trials (default: the session's).",
        ),
    ] = None,
    json_out: JsonOption = False,
    units_choice: UnitsOption = UNITS_DEFAULT,
    from_here: Annotated[
        bool,
        typer.Option(
            "--from-here",
            help="Go on although the robot is not where the next trial starts "
            f"(beyond {POSITION_TOLERANCE_M:g} m or {HEADING_TOLERANCE_DEG:g} deg); "
            "the trial then starts where the robot stands.",
        ),
    ] = False,
) -> None:
    """Continue an interrupted session: no trial lost, none counted twice.

    A trial cut off before or during its motion is voided and redone; one whose
    motion finished resumes at its next missing measurement. The session is
    locked before the port is opened: one in use is refused (exit 2). A robot
    that is not where the next trial starts is refused (exit 2) unless --from-here.
    """
    console = Console(stderr=True)
    system = unit_system(units_choice)
    spec = SessionSpec(
        session, "resume", measure=measure, port=port, baud=baud, truth_socket=truth_socket
    )
    with session_exit_codes(console, json_out):
        prepared = prepared_or_exit(preflight(spec), console)
        with open_session(prepared, say_opened(console)) as opened:
            if opened.torn is not None:
                console.print(f"[yellow]warning[/]: {opened.torn.describe()}")
            state = opened.state
            assert state.plan is not None
            console.print(
                f"resuming {session}: {len(state.completed)} of "
                f"{units.plural(state.plan.n_trials, 'trial')} done"
                + (f", trial {state.open_trial.trial} open" if state.open_trial else "")
            )
            console.print(f"robot: {prepared.line.describe()}", soft_wrap=True, markup=False)
            refused: list[StartPose] = []

            def start_check(start: StartPose) -> None:
                console.print(f"robot: {start.describe()}")
                if not start.ok and from_here:
                    console.print("[yellow]--from-here[/]: the trial starts where it stands")
                elif not start.ok:
                    refused.append(start)
                    refuse_off_start(start)

            outcome = run_with_progress(console, opened, system, start_check)
            report_run(console, outcome)
    finish(outcome, json_out, console, system=system, code=EXIT_BAD_INPUT if refused else None)


def register(app: typer.Typer) -> None:
    """Add ``resume`` to the ``odohil`` app."""
    app.command("resume")(resume)
