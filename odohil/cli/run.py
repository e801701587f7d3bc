"""``odohil run``: an unattended calibration session on the robot.

Also the pieces ``odohil resume`` and ``odohil demo`` share: opening the
robot and its truth side channel, building the measurement source, running
the engine with a progress bar, the final summary and the exit statuses of
:mod:`odohil.cli.exit_codes` (0 done, 1 error, 2 bad input or session in use,
4 stop unconfirmed, 128 + N signal N). The session is locked before the
robot's port is opened, so a second run on it sends nothing.
"""

from __future__ import annotations

import contextlib
import json
import math
import signal
import time
from collections.abc import Collection, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.console import Console
from rich.markup import escape
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

from odohil import units
from odohil.cli.exclude import EXCLUDE_HELP, check_exclude, parse_exclude
from odohil.cli.exit_codes import (
    EXIT_BAD_INPUT,
    EXIT_ERROR,
    EXIT_STOP_UNCONFIRMED,
    exit_for_outcome,
    exit_for_signal,
)
from odohil.cli.line import (
    Line,
    open_truth_client,
    register_fake_urls,
    resolve_line,
    truth_available,
)
from odohil.cli.options import UNITS_DEFAULT, UnitsOption, bounded, unit_system
from odohil.cli.render import parameters_table
from odohil.cli.robot_option import ROBOT_HELP, robot_callback
from odohil.cli.verdict import export_refusal_lines, outcome_line
from odohil.errors import (
    JournalError,
    OdohilError,
    ParameterError,
    RobotDescriptionError,
    StopUnconfirmedError,
    TrialFileError,
)
from odohil.science.estimators import EstimateResult
from odohil.science.pose_selection import check_redundancy
from odohil.science.robot_description import RobotDescription
from odohil.session.engine import (
    IncrementalLiveEstimator,
    MotionSettings,
    SessionEngine,
    StartCheck,
    StopOutcome,
    start_session,
)
from odohil.session.events import Solved, Void
from odohil.session.floor_space import check_floor
from odohil.session.journal import Journal, Record
from odohil.session.outcome import EstimateOutcome, estimate_state
from odohil.session.plan import Plan
from odohil.session.pose_source import PoseSource
from odohil.session.pose_sources import (
    Connection,
    OpenContext,
    Preflight,
    check_measure,
    open_measure,
    parse_measure,
)
from odohil.session.preflight import (
    check_new_session,
    check_trials_per_design,
    turn_designs,
)
from odohil.session.robot import Robot
from odohil.session.robots import open_robot
from odohil.session.signals import signal_name, signal_of, signals_raise
from odohil.session.start_pose import StartPose
from odohil.session.state import SessionState, load_session
from odohil.session.tape_records import MeasurementsRejected, Remeasured

MAY_STILL_MOVE = "the robot may still be moving: use its emergency stop"
"""What odohil says, prominently, when it could not confirm the robot's stop."""

_PLAN_HELP = (
    'Designs and trial counts, e.g. "k=1,l=6,n=30;k=20,l=0.5,n=30" '
    "(k pairs, l metres, n trials, optional variant=turn|reverse)."
)


@contextlib.contextmanager
def connect(line: Line, truth_socket: str | None) -> Iterator[tuple[Robot, Any]]:
    """The robot on ``line`` (through the backend its protocol names) and its
    truth side channel (None when there is none).

    A backend's in-process fake port (``fakerobot://``, ``fakecreate2://``)
    carries its own truth (on the backend's ``transport``, the open port); a
    pty fake robot needs ``truth_socket``, read by the client its backend
    declares (odohil/session/robots.py ``fake_hooks``).
    The robot is closed (stopped) on exit.
    """
    register_fake_urls(line.port)
    robot = open_robot(line.protocol, line.port, line.baud, line.robot)
    transport = robot.transport
    truth: Any = None
    try:
        if truth_socket:
            truth = open_truth_client(line, truth_socket)
        elif hasattr(transport, "truth"):
            truth = transport
        yield robot, truth
    finally:
        try:
            robot.close()
        finally:
            if truth is not None and hasattr(truth, "close") and truth is not transport:
                truth.close()


class ProgressObserver:
    """A rich progress bar of completed trials, on stderr, with notes."""

    def __init__(
        self,
        console: Console,
        state: SessionState,
        system: units.UnitSystem = units.DEFAULT_UNIT_SYSTEM,
        measurer: str = "the simulated operator",
    ) -> None:
        assert state.plan is not None
        self.console = console
        self.system = system
        self.measurer = measurer
        self.remeasured: dict[int, None] = {}  # trial numbers, in order
        self.progress = Progress(
            TextColumn("[bold]trials"),
            BarColumn(),
            MofNCompleteColumn(),
            TimeElapsedColumn(),
            TextColumn("{task.description}"),
            console=console,
            transient=False,
        )
        self.task = self.progress.add_task(
            "", total=state.plan.n_trials, completed=len(state.completed)
        )

    def record(self, record: Record, state: SessionState) -> None:
        """Advance on each solved trial; print voids and rejections."""
        event = record.event
        if isinstance(event, Solved):
            self.progress.update(self.task, completed=len(state.completed))
        elif isinstance(event, Void):
            self.progress.console.print(
                f"trial {event.trial} attempt {event.attempt} void: {event.reason}"
            )
        elif isinstance(event, MeasurementsRejected):
            self.progress.console.print(
                f"trial {event.trial}: the distances {self.measurer} took fit no "
                f"rigid motion, so {self.measurer} measured them again: the check at work; "
                "nothing is lost and the trial counts once (the reason is in the journal).",
                soft_wrap=True,
                highlight=False,
            )
        elif isinstance(event, Remeasured) and not event.kept:
            self.remeasured.setdefault(event.trial, None)

    def remeasure_summary(self) -> str | None:
        """One line for every distance the slip check had taken again (None if none)."""
        if not self.remeasured:
            return None
        trials = list(self.remeasured)
        return (
            f"In {units.plural(len(trials), 'trial')} ({', '.join(map(str, trials))}) the "
            f"slip check doubted a distance and {self.measurer} measured it again: the check "
            "at work; nothing is lost and each trial counts once."
        )

    def estimated(self, result: EstimateResult, state: SessionState) -> None:
        """Show the live E_R beside the bar."""
        e_r = result.parameter("E_R").value
        if math.isfinite(e_r):
            value = units.parameter_in("E_R", e_r, self.system)
            unit = units.parameter_unit("E_R", self.system)
            self.progress.update(self.task, description=f"E_R {value:+.4g} {unit}")


@dataclass(frozen=True)
class Outcome:
    """How a session run ended: exit code, the final estimate (if any), and
    for ``--json`` how it ended (``status``: finished, interrupted, error,
    stop unconfirmed; ``details``: the signal, whether the stop was confirmed,
    the partial estimate of an interrupted run)."""

    exit_code: int
    estimate: EstimateResult | None
    status: str = "finished"
    details: Mapping[str, Any] = field(default_factory=dict)


def execute(
    journal: Journal,
    state: SessionState,
    robot: Robot,
    source: PoseSource,
    connection: Mapping[str, Any],
    console: Console,
    motion: MotionSettings | None = None,
    start_check: StartCheck | None = None,
    exclude: frozenset[int] = frozenset(),
    system: units.UnitSystem = units.DEFAULT_UNIT_SYSTEM,
    measurer: str = "the simulated operator",
) -> Outcome:
    """Run the engine with a progress bar; map failures to exit codes (3 when
    the final estimate's verdict is not trusted). ``exclude``: trial numbers
    left out of the live and final estimate (the journal keeps them).

    The engine journals ``stopped`` and stops the robot before an error gets here.
    """
    ran = run_engine(
        journal, state, robot, source, connection, console, motion, start_check, exclude,
        system, measurer,
    )  # fmt: skip
    if isinstance(ran, Outcome):
        return ran
    fitted = final_estimate(ran, exclude)
    console.print(outcome_line(fitted), highlight=False)
    for line in export_refusal_lines(fitted):
        console.print(line, highlight=False)
    verdict = {"status": fitted.status, "reasons": [fitted.problem]}
    details = {} if fitted.result else {"verdict": verdict}
    return Outcome(exit_for_outcome(fitted), fitted.result, details=details)


def run_engine(
    journal: Journal,
    state: SessionState,
    robot: Robot,
    source: PoseSource,
    connection: Mapping[str, Any],
    console: Console,
    motion: MotionSettings | None = None,
    start_check: StartCheck | None = None,
    exclude: frozenset[int] = frozenset(),
    system: units.UnitSystem = units.DEFAULT_UNIT_SYSTEM,
    measurer: str = "the simulated operator",
) -> SessionState | Outcome:
    """Run the engine with a progress bar: the session's final state, or the
    :class:`Outcome` of a run that ended early (its failure mapped to an exit
    code, the robot's stop and the journal checked on the way out)."""
    folder = journal.folder
    observer = ProgressObserver(console, state, system, measurer)
    engine = SessionEngine(
        journal,
        state,
        robot,
        source,
        estimator=IncrementalLiveEstimator(exclude),
        observer=observer,
        motion=motion,
        connection=connection,
        start_check=start_check or show_start(console),
    )
    observer.progress.start()
    try:
        final = engine.run()
    except StopUnconfirmedError as exc:
        observer.progress.stop()
        report_unconfirmed(console, exc, engine.stop_outcome, folder)
        return ended(EXIT_STOP_UNCONFIRMED, "stop unconfirmed", engine, exclude, str(exc))
    except KeyboardInterrupt as exc:
        observer.progress.stop()
        signum = signal_of(exc)
        console.print(f"[yellow]interrupted[/] ({interrupt_text(exc)})", soft_wrap=True)
        report_stop(console, engine.stop_outcome, folder)
        return ended(
            exit_for_signal(signum),
            "interrupted",
            engine,
            exclude,
            interrupt_text(exc),
            signal=signal_name(signum),
        )
    except OdohilError as exc:
        observer.progress.stop()
        console.print(f"[red]error[/]: {exc}", soft_wrap=True)
        report_stop(console, engine.stop_outcome, folder)
        return ended(EXIT_ERROR, "error", engine, exclude, str(exc))
    finally:
        observer.progress.stop()
        if (summary := observer.remeasure_summary()) is not None:
            console.print(summary, soft_wrap=True, highlight=False)
    return final


def interrupt_text(exc: BaseException) -> str:
    """What ended the run, in words: "Ctrl-C" or "SIGTERM received" (never
    an exception's class name)."""
    signum = signal_of(exc)
    if signum == signal.SIGINT:
        return "Ctrl-C"
    return str(exc) or f"{signal_name(signum)} received"


def ended(
    code: int,
    status: str,
    engine: SessionEngine,
    exclude: Collection[int],
    message: str,
    **details: Any,
) -> Outcome:
    """The outcome of a run that did not finish: its status, what was checked
    on the way out (the robot's stop, the journal) and the estimate of the
    trials done so far (None when they are too few)."""
    stop = engine.stop_outcome
    state = engine.state
    # what is on disk: a signal may land between a record and the state it makes
    with contextlib.suppress(OdohilError):
        state = load_session(engine.journal.folder).state
    info: dict[str, Any] = {
        **details,
        "message": message,
        "stop_confirmed": None if stop is None else stop.robot_stopped,
        "journaled": None if stop is None else stop.journaled,
        "trials_done": len(state.completed),
        "session": str(engine.journal.folder),
    }
    fitted = final_estimate(state, exclude)
    partial = fitted.result
    if partial is None:
        info["partial_estimate_note"] = fitted.problem
    info["partial_estimate"] = None if partial is None else partial.to_json_dict()
    return Outcome(code, None, status, info)


def final_estimate(state: SessionState, exclude: Collection[int] = ()) -> EstimateOutcome:
    """A session's estimate and verdict by the one recipe
    (odohil/session/outcome.py): every solved trial but the ambiguous ones and
    those in ``exclude`` (numbers of trials not yet done are ignored)."""
    done = {t.trial for t in state.completed}
    return estimate_state(state, [t for t in exclude if t in done])


ALLOW_FEW_HELP = (
    "Run a plan with fewer trials a design than the planner's minimum (10); "
    "its estimate is then not exported without --force."
)
ALLOW_TURNS_HELP = (
    "Run `turn` designs on a robot whose turns carry error (\\[robot] turns_exact = false); "
    "the estimate is then not trusted."
)


def warn_turns(console: Console, plan: Plan, description: RobotDescription) -> None:
    """Warn when the plan turns in place on a robot whose turns carry error."""
    turns = turn_designs(plan, description)
    if turns:
        console.print(
            f"[yellow]warning:[/] turn designs on a robot whose turns carry error "
            f"({', '.join(turns)}): the estimate will not be trusted; use variant=reverse",
            soft_wrap=True,
        )


def report_stop(
    console: Console,
    outcome: StopOutcome | None,
    folder: Path,
    continue_with: str | None = None,
) -> None:
    """Say what was checked on the way out: the robot's stop, then the journal,
    and the command that continues the session (``continue_with``; default
    ``odohil resume FOLDER``).

    "robot stopped" only when the robot reported it; "journaled" only when the
    closing record is on disk.
    """
    again = continue_with or f"odohil resume {folder}"
    if outcome is None:
        return
    if outcome.robot_stopped:
        console.print(f"robot stopped (it reports {escape(outcome.detail)})", soft_wrap=True)
    else:
        console.print(f"[bold red]{MAY_STILL_MOVE}[/]: {escape(outcome.detail)}", soft_wrap=True)
    if outcome.journaled:
        console.print(
            f"session journaled in {folder}; continue with `{again}`",
            soft_wrap=True,
        )
    else:
        console.print(
            f"[bold red]the journal could not be written[/]: {escape(outcome.journal_error)}; "
            f"the records before this failure are kept in {folder}; free the disk, then "
            f"`{again}`",
            soft_wrap=True,
        )


def report_unconfirmed(
    console: Console, exc: StopUnconfirmedError, outcome: StopOutcome | None, folder: Path
) -> None:
    """The stop could not be confirmed: say so first and prominently, then why."""
    console.print(f"[bold red]WARNING: {MAY_STILL_MOVE}[/]", soft_wrap=True)
    if exc.__cause__ is not None:
        cause = exc.__cause__
        if isinstance(cause, KeyboardInterrupt):
            why = interrupt_text(cause)
        else:
            why = str(cause) or "an error without a message"
        console.print(f"the run ended on: {why}", soft_wrap=True, markup=False)
    if outcome is None:
        console.print(f"st sent but not confirmed: {exc}", soft_wrap=True, markup=False)
        return
    report_stop(console, outcome, folder)


def show_start(console: Console) -> StartCheck:
    """A start check that prints where the encoders read (with the heading)."""

    def check(start: StartPose) -> None:
        console.print(f"robot: {start.describe()}")

    return check


def print_summary(
    result: EstimateResult,
    console: Console,
    truth: Mapping[str, float] | None = None,
    system: units.UnitSystem = units.DEFAULT_UNIT_SYSTEM,
) -> None:
    """The estimate as a table in ``system``'s units, with the true values
    (SI, by name) beside when known."""
    title = f"estimate ({result.method}, {units.plural(result.n_trials, 'trial')})"
    console.print(parameters_table(result, system, title, truth))


def _ctrl_c(signum: int, frame: Any) -> None:
    raise KeyboardInterrupt("Ctrl-C")


@contextlib.contextmanager
def ctrl_c_in_words() -> Iterator[None]:
    """Within: Ctrl-C raises a KeyboardInterrupt that says "Ctrl-C", so what the
    engine journals and what the operator reads name the key, not a class
    (main thread only; the previous handler comes back afterwards)."""
    try:
        previous = signal.signal(signal.SIGINT, _ctrl_c)
    except ValueError:  # not the main thread
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


@contextlib.contextmanager
def session_exit_codes(console: Console, json_out: bool = False) -> Iterator[None]:
    """Make every signal that ends a process (odohil/session/signals.py) end the
    command as Ctrl-C does, and turn
    what escapes into its exit status: a signal 128 + N, an unconfirmed stop 4,
    a session that cannot be opened or is in use 2, any other odohil or OS
    error 1 (the robot was already stopped and the journal written below).
    With ``json_out`` an interrupt before the session ran still prints one
    JSON object saying so."""
    try:
        with signals_raise(), ctrl_c_in_words():
            yield
    except KeyboardInterrupt as exc:
        console.print(f"[yellow]interrupted[/] ({interrupt_text(exc)})", soft_wrap=True)
        if json_out:
            signum = signal_of(exc)
            document = {
                "status": "interrupted",
                "signal": signal_name(signum),
                "message": interrupt_text(exc) + " before the session ran: nothing moved",
                "stop_confirmed": None,
                "partial_estimate": None,
            }
            typer.echo(json.dumps(document))
        raise typer.Exit(exit_for_signal(signal_of(exc))) from None
    except StopUnconfirmedError as exc:
        console.print(f"[bold red]WARNING: {MAY_STILL_MOVE}[/]: {escape(str(exc))}", soft_wrap=True)
        raise typer.Exit(EXIT_STOP_UNCONFIRMED) from None
    except (ParameterError, RobotDescriptionError, TrialFileError, JournalError) as exc:
        # found before anything moved
        console.print(f"[red]error[/]: {escape(str(exc))}", soft_wrap=True)
        raise typer.Exit(EXIT_BAD_INPUT) from None
    except (OdohilError, OSError) as exc:
        console.print(f"[red]error[/]: {escape(str(exc))}", soft_wrap=True)
        raise typer.Exit(EXIT_ERROR) from None


@contextlib.contextmanager
def session_input(console: Console) -> Iterator[None]:
    """A session that cannot be created or opened (in use, missing, finished,
    corrupt) is bad input: its message, exit 2; nothing was sent to the robot."""
    try:
        yield
    except JournalError as exc:
        console.print(f"[red]error[/]: {exc}", soft_wrap=True)
        raise typer.Exit(EXIT_BAD_INPUT) from None


def refuse_unredundant(description: RobotDescription, plan: Plan, console: Console) -> None:
    """Pre-flight: exit 2 (bad input, nothing moved) when the description's cross
    distances cannot disambiguate the plan's designs."""
    try:
        check_redundancy(description, [item.design for item in plan.items])
    except OdohilError as exc:
        console.print(f"[red]error[/]: {exc}")
        raise typer.Exit(EXIT_BAD_INPUT) from None


def checked_exclude(text: str | None, n_trials: int, console: Console) -> frozenset[int]:
    """``--exclude``'s trial numbers, each within the plan's 1..n_trials (else exit 2)."""
    try:
        exclude = parse_exclude(text)
        check_exclude(exclude, range(1, n_trials + 1))
    except OdohilError as exc:
        console.print(f"[red]error[/]: {exc}")
        raise typer.Exit(EXIT_BAD_INPUT) from None
    return exclude


def default_session_folder() -> Path:
    """``odohil-session-YYYYmmdd-HHMMSS`` in the current directory."""
    return Path(f"odohil-session-{time.strftime('%Y%m%d-%H%M%S')}")


def run(
    port: Annotated[
        str | None,
        typer.Option(
            "--port",
            help="Serial device, pty path or pyserial URL (default: robot.toml \\[serial] port).",
        ),
    ] = None,
    *,
    robot_file: Annotated[Path, typer.Option("--robot", callback=robot_callback, help=ROBOT_HELP)],
    plan_text: Annotated[str, typer.Option("--plan", help=_PLAN_HELP)],
    measure: Annotated[
        str,
        typer.Option(
            "--measure",
            help="`fake` (the fake robot's true pose), a trial file (CSV), "
            "tcp://HOST:PORT (a motion-capture stream, docs/motion-capture.md), or the form "
            "of another installed pose source (docs/pose-sources.md).",
        ),
    ],
    session: Annotated[
        Path | None,
        typer.Option("--session", help="Session folder (default: odohil-session-<time> here)."),
    ] = None,
    truth_socket: Annotated[
        str | None,
        typer.Option("--truth-socket", help="The fake robot's truth socket (for --measure fake)."),
    ] = None,
    seed: Annotated[
        int,
        typer.Option(
            "--seed", callback=bounded("seed"), help="Seed of the simulated tape noise (fake)."
        ),
    ] = 0,
    baud: Annotated[
        int | None,
        typer.Option(
            "--baud",
            callback=bounded("baud"),
            help="Line speed (default: robot.toml \\[serial] baud, else the robot's default).",
        ),
    ] = None,
    json_out: Annotated[
        bool,
        typer.Option(
            "--json",
            help="Print one JSON object (SI): the final estimate (as estimate --json) with "
            '"status": "finished"; when interrupted or failed, the status, the signal, '
            "whether the stop was confirmed and the partial estimate.",
        ),
    ] = False,
    exclude_text: Annotated[str | None, typer.Option("--exclude", help=EXCLUDE_HELP)] = None,
    units_choice: UnitsOption = UNITS_DEFAULT,
    allow_turns: Annotated[bool, typer.Option("--allow-turns", help=ALLOW_TURNS_HELP)] = False,
    allow_few: Annotated[bool, typer.Option("--allow-few-trials", help=ALLOW_FEW_HELP)] = False,
) -> None:
    """Run a calibration session unattended: n trials, no prompts, journaled.

    Exit 0 when the final estimate is trusted, 3 when it is printed but not.
    """
    console = Console(stderr=True)
    folder = session or default_session_folder()
    system = unit_system(units_choice)
    with session_exit_codes(console, json_out):
        checked = check_new_session(plan_text, robot_file, folder, allow_turns)  # nothing moved
        plan, description, toml = checked.plan, checked.description, checked.toml
        check_trials_per_design(plan, allow_few)
        warn_turns(console, plan, description)
        exclude = checked_exclude(exclude_text, plan.n_trials, console)
        option = parse_measure(measure)
        if option.floor_marks:  # the tape's cross distances must tell the designs apart
            refuse_unredundant(description, plan, console)
        try:
            check_floor(plan, description)
        except ParameterError as exc:
            console.print(f"[red]error[/]: {exc}; nothing moved")
            raise typer.Exit(EXIT_BAD_INPUT) from None
        line = resolve_line(description, port, baud, str(robot_file))
        check_measure(option, Preflight(description, plan, truth_available(line, truth_socket)))
        settings = {
            **line.to_json(),
            "truth_socket": truth_socket,
            "seed": seed,
            "trial_file": None,
            **option.journal_settings(),
        }
        with open_measure(option, OpenContext(description, seed)) as opened:
            if opened.note:
                console.print(opened.note, soft_wrap=True)
            with session_input(console):
                journal, state = start_session(
                    folder, toml, plan, measure=option.kind, settings=settings,
                    robot_path=str(robot_file),
                )  # fmt: skip
            console.print(f"session {folder}")
            console.print(f"robot: {line.describe()}", soft_wrap=True, markup=False)
            with journal, connect(line, truth_socket) as (robot, truth):
                source = opened.make(Connection(robot, truth))
                outcome = execute(
                    journal, state, robot, source, settings, console, exclude=exclude, system=system
                )
    finish(outcome, json_out, console, system=system)


def finish(
    outcome: Outcome,
    json_out: bool,
    console: Console,
    extra: Mapping[str, Any] | None = None,
    truth: Mapping[str, float] | None = None,
    system: units.UnitSystem = units.DEFAULT_UNIT_SYSTEM,
) -> None:
    """Print the summary (a table on stdout, or one JSON object) and exit with
    the outcome's code. With ``json_out`` a run that did not finish prints its
    status and partial estimate (:func:`ended`) instead of nothing."""
    if json_out:
        if outcome.estimate is not None:
            document = {"status": outcome.status, **outcome.estimate.to_json_dict()}
        else:
            document = {"status": outcome.status, "exit_code": outcome.exit_code}
            document.update(outcome.details)
        typer.echo(json.dumps({**document, **(extra or {})}))
    elif outcome.estimate is not None:
        print_summary(outcome.estimate, Console(width=max(110, Console().width)), truth, system)
    if outcome.exit_code:
        raise typer.Exit(outcome.exit_code)


def register(app: typer.Typer) -> None:
    """Add ``run`` to the ``odohil`` app."""
    app.command("run")(run)
