"""``odohil resume``: continue a session exactly where its journal stops."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console

from odohil import units
from odohil.cli.exit_codes import EXIT_BAD_INPUT
from odohil.cli.line import resolve_line, truth_available
from odohil.cli.options import UNITS_DEFAULT, UnitsOption, bounded, unit_system
from odohil.cli.run import (
    Outcome,
    connect,
    execute,
    finish,
    session_exit_codes,
    session_input,
)
from odohil.errors import InitError
from odohil.session.engine import description_of, resume_session
from odohil.session.floor_space import check_floor
from odohil.session.pose_sources import (
    OPERATOR,
    Connection,
    OpenContext,
    Preflight,
    check_measure,
    journaled_measure,
    open_measure,
    parse_measure,
)
from odohil.session.preflight import check_session_folder
from odohil.session.start_pose import (
    HEADING_TOLERANCE_DEG,
    POSITION_TOLERANCE_M,
    StartPose,
    refuse_off_start,
)


def resume(
    session: Annotated[Path, typer.Argument(help="The session folder to continue.")],
    port: Annotated[
        str | None, typer.Option("--port", help="Serial port (default: the session's).")
    ] = None,
    truth_socket: Annotated[
        str | None,
        typer.Option("--truth-socket", help="Fake robot truth socket (default: the session's)."),
    ] = None,
    baud: Annotated[
        int | None,
        typer.Option(
            "--baud", callback=bounded("baud"), help="Line speed (default: the session's)."
        ),
    ] = None,
    measure: Annotated[
        str | None,
        typer.Option(
            "--measure",
            help="`fake`, a trial file (CSV), tcp://HOST:PORT (motion capture) or another "
            "installed pose source's form for the remaining trials (default: the session's).",
        ),
    ] = None,
    json_out: Annotated[
        bool,
        typer.Option(
            "--json",
            help="Print one JSON object (SI), as run --json: the final estimate, or the "
            "status and partial estimate of a run that did not finish.",
        ),
    ] = False,
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
    with session_exit_codes(console, json_out):
        with session_input(console):
            check_session_folder(session)
            resumed = resume_session(session)
        with resumed.journal:
            if resumed.torn is not None:
                console.print(f"[yellow]warning[/]: {resumed.torn.describe()}")
            state = resumed.state
            if state.header.measure == OPERATOR:
                raise InitError(
                    f"{session} is a wizard session (the operator measures): continue it "
                    f"with `odohil wizard --port PORT --session {session}`"
                )
            settings = dict(state.header.settings)
            description = description_of(state)  # before the port opens
            robot_path = state.header.robot_path or "robot.toml"
            line = resolve_line(description, port, baud, robot_path, journaled=settings)
            socket_path = truth_socket or settings.get("truth_socket")
            option = journaled_measure(state.header.measure, state.header.settings)
            if measure is not None:
                option = parse_measure(measure)
                settings.update(trial_file=None, mocap_url=None)
                settings.update(option.journal_settings())
            done = len(state.completed)
            assert state.plan is not None
            check_floor(state.plan, description_of(state))
            seed = int(settings.get("seed") or 0)
            available = truth_available(line, socket_path)  # before the port opens:
            check_measure(option, Preflight(description, state.plan, available))
            console.print(
                f"resuming {session}: {done} of "
                f"{units.plural(state.plan.n_trials, 'trial')} done"
                + (f", trial {state.open_trial.trial} open" if state.open_trial else "")
            )
            console.print(f"robot: {line.describe()}", soft_wrap=True, markup=False)
            with (
                open_measure(option, OpenContext(description, seed)) as opened,  # before the port
                connect(line, socket_path) as (robot, truth),
            ):
                if opened.note:
                    console.print(opened.note, soft_wrap=True)
                source = opened.make(Connection(robot, truth))
                connection = {**settings, **line.to_json()}
                connection["truth_socket"] = socket_path
                refused: list[StartPose] = []

                def start_check(start: StartPose) -> None:
                    console.print(f"robot: {start.describe()}")
                    if not start.ok and from_here:
                        console.print("[yellow]--from-here[/]: the trial starts where it stands")
                    elif not start.ok:
                        refused.append(start)
                        refuse_off_start(start)

                outcome = execute(
                    resumed.journal, state, robot, source, connection, console,
                    start_check=start_check, system=system,
                )  # fmt: skip
                if refused:
                    outcome = Outcome(EXIT_BAD_INPUT, None)
    finish(outcome, json_out, console, system=system)


def register(app: typer.Typer) -> None:
    """Add ``resume`` to the ``odohil`` app."""
    app.command("resume")(resume)
