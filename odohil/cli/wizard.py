"""``odohil wizard``: the operator's guide beside the robot, one trial at a time.

Pre-flight checks first (nothing moves until all pass); then per trial: mark
the floor, watch the motion, type the tape distances (checked, re-asked with
the reason), see the live estimate. Ctrl-C (or SIGTERM, SIGHUP, SIGQUIT)
stops the robot, waits for it to report that it stopped, journals and exits
128 + N; if the stop cannot be confirmed it says the robot may still be
moving and exits 4. A second Ctrl-C before the engine's stop has begun sends
one ``st`` and exits at once (4 unless the robot confirmed the stop); during
the stop itself (at most 2 s) it is held. The session is locked before the
port is opened; one in use is refused (exit 2). Running the wizard again on
the same ``--session`` continues where the journal stops.
"""

from __future__ import annotations

import math
import os
import sys
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any, NoReturn

import typer
from rich.console import Console
from rich.markup import escape

from odohil import units
from odohil.cli.exit_codes import (
    EXIT_BAD_INPUT,
    EXIT_ERROR,
    EXIT_INTERRUPTED,
    EXIT_OK,
    EXIT_STOP_UNCONFIRMED,
    EXIT_UNTRUSTED,
    exit_for_outcome,
    exit_for_signal,
)
from odohil.cli.line import Line, register_fake_urls, resolve_line
from odohil.cli.options import UNITS_DEFAULT, UnitsOption, bounded, unit_system
from odohil.cli.render import MotionProgress, check_line, estimate_panel
from odohil.cli.robot_option import ROBOT_HELP, robot_callback
from odohil.cli.run import (
    ALLOW_TURNS_HELP,
    MAY_STILL_MOVE,
    default_session_folder,
    final_estimate,
    interrupt_text,
    report_stop,
    warn_turns,
)
from odohil.cli.verdict import export_refusal_lines, outcome_line
from odohil.driver.odometry import OdometrySample
from odohil.errors import (
    InconsistentMeasurementError,
    MeasurementError,
    OdohilError,
    StopUnconfirmedError,
)
from odohil.science.estimators import EstimateResult
from odohil.science.planner import DEFAULT_MAX_LEG_M
from odohil.science.pose_selection import check_redundancy
from odohil.science.robot_description import RobotDescription
from odohil.session.engine import (
    IncrementalLiveEstimator,
    SessionEngine,
    StartCheck,
    description_of,
    resume_session,
    start_session,
)
from odohil.session.events import Finished, MotionStart, Solved, Void
from odohil.session.interrupts import Interrupts, wait_readable
from odohil.session.journal import Journal, Record, journal_path
from odohil.session.plan import Plan, check_session_plan, parse_plan
from odohil.session.pose_sources import OPERATOR
from odohil.session.preflight import (
    Check,
    check_session_folder,
    check_turns,
    default_variant,
    estimable_check,
    floor_check,
    leg_check,
)
from odohil.session.robot import Robot
from odohil.session.robot_file import load_robot_description, read_robot_toml
from odohil.session.robots import open_robot
from odohil.session.robots import parse_description as parse_robot_description
from odohil.session.signals import signal_of, signals_raise
from odohil.session.sources import OperatorSource, TrialContext
from odohil.session.start_pose import StartPose, pose_text, sample_pose
from odohil.session.state import SessionState, load_session
from odohil.session.tape_entry import INSTRUCTIONS, TapeEntries, parse_optional_metres

DEFAULT_PLAN = "k=1,l=6,n=30;k=20,l=0.5,n=30"
_STYLE = {"refused": "[red]refused:[/] ", "check": "[yellow]check:[/] ", "no_back": "[yellow]"}


@dataclass
class WizardPrompts:
    """The :class:`~odohil.session.sources.OperatorPrompts` of the wizard: it reads
    lines and renders; what they mean is odohil/session/tape_entry.py's."""

    console: Console
    description: RobotDescription
    interrupts: Interrupts
    progress: MotionProgress

    def __post_init__(self) -> None:
        self.entries = TapeEntries(self.description)

    def _input(self, prompt: str) -> str:
        try:
            self.console.print(prompt, end="")
            wait_readable(sys.stdin)
            return input()
        except EOFError:
            raise MeasurementError("the input ended (no operator at the terminal)") from None

    def _context(self, ctx: TrialContext, resumed: bool = True) -> None:
        """The trial's header once per attempt; on a resumed one also what was entered."""
        if not self.entries.first_sight(ctx):
            return
        note = " [bold](resumed: the motion is done, its marks are on the floor)[/]"
        self.console.print(
            f"\n[bold]Trial {ctx.trial}/{ctx.n_trials}[/] (attempt {ctx.attempt}): "
            f"{ctx.design.label()}, {ctx.design.distance_m:g} m of driving"
            f"{note if resumed else ''}."
        )
        if resumed and ctx.measurements:
            values = zip(ctx.labels, ctx.measurements, strict=False)
            entered = ", ".join(f"{label} = {value:.4f} m" for label, value in values)
            left = units.plural(len(ctx.labels) - len(ctx.measurements), "distance")
            self.console.print(f"Already entered and saved: {entered}; {left} to go.")

    def confirm_start_marks(self, ctx: TrialContext) -> None:
        """Ask for the start marks."""
        self._context(ctx, resumed=False)
        names = ", ".join(self.description.screw_names)
        self._input(
            f"Mark the floor at the {len(self.description.screws)} screws ({names}), "
            "keep clear of the robot, then press Enter to start the motion: "
        )

    def confirm_end_marks(self, ctx: TrialContext) -> None:
        """The motion is over: ask for the end marks."""
        self.progress.stop()
        self.interrupts.in_motion = False
        self.interrupts.check()
        self._context(ctx)
        if (pose := ctx.encoder_end_pose) is not None:
            self.console.print(
                f"Motion done; encoders say x={pose[0]:+.4f} m y={pose[1]:+.4f} m "
                f"heading {math.degrees(pose[2]):+.2f} deg from the start."
            )
        self._input("Mark the floor at the screws again (end marks), then press Enter: ")

    def ask_distance(self, ctx: TrialContext, index: int) -> float:
        """Distance ``index``, metres, as the attempt's :class:`TapeEntry` hands it over."""
        self._context(ctx)
        entry, new = self.entries.entry(ctx)
        if new:
            self.console.print(INSTRUCTIONS)
        while (value := entry.take(index)) is None:
            reply = entry.feed(self._input(entry.question().prompt))
            if reply.message:
                self.console.print(_STYLE.get(reply.kind, "") + reply.message)
        if index in entry.kept:
            self.console.print(f"{ctx.labels[index]}: {value:.4f} m kept")
        return value

    def _optional(self, ctx: TrialContext, doubt: str, prompt: str, label: str) -> float | None:
        self._context(ctx)
        self.console.print(doubt)
        while True:
            try:
                return parse_optional_metres(self._input(prompt), label)
            except MeasurementError as exc:
                self.console.print(f"[red]refused:[/] {exc}; type it again")

    def ask_remeasure(self, ctx: TrialContext, index: int, reason: str) -> float | None:
        """The slip check doubts the trial: ask for the suspect distance again."""
        label, typed = ctx.labels[index], ctx.measurements[index]
        keep = f"you typed {typed:.4f}; press Enter to keep it"
        prompt = f"Re-measure {label}, metres ({keep}): "
        return self._optional(ctx, f"[yellow]check the marks:[/] {reason}", prompt, label)

    def ask_extra_distance(self, ctx: TrialContext, label: str, reason: str) -> float | None:
        """The trial is ambiguous: ask for one more cross distance, named by its screws."""
        skip = "press Enter if you cannot; the trial is then left out"
        prompt = f"Measure one more distance, {label}, metres ({skip}): "
        return self._optional(ctx, f"[yellow]two poses fit these marks:[/] {reason}", prompt, label)

    def start_check(self, robot: Robot) -> StartCheck:
        """Show where the robot stands; off the next trial's start, ask the
        operator to put it back there (or type 'here'), then zero the encoders there."""

        def check(start: StartPose) -> None:
            self.console.print(f"Robot: {start.describe()}")
            if start.ok or start.expected is None:
                return
            answer = self._input(
                f"[bold]Put the robot back where trial {start.trial} starts[/] (the end marks "
                "of the last trial, or this trial's start marks), then press Enter; or type "
                "'here' to start the trial where it stands: "
            )
            if answer.strip().lower() == "here":
                self.console.print("The trial starts where the robot stands.")
                return
            robot.zero(start.expected)
            self.console.print("Encoders set to the trial's start.")

        return check

    def show_rejection(self, ctx: TrialContext, rejection: InconsistentMeasurementError) -> None:
        """Say why; only the distances the rejection names are asked for again."""
        kept = self.entries.rejected(ctx, rejection)
        again = ", ".join(label for i, label in enumerate(ctx.labels) if i not in kept)
        what = f"only {again} (the other distances are kept)" if kept else "all its distances"
        self.console.print(
            f"[red]These distances fit no rigid motion:[/] {rejection}\nMeasure again {what}."
        )


@dataclass
class WizardObserver:
    """Sees the session unfold: motion bar, solved pose, and the live estimate
    by the one recipe (odohil/session/outcome.py)."""

    console: Console
    interrupts: Interrupts
    progress: MotionProgress
    system: units.UnitSystem = units.DEFAULT_UNIT_SYSTEM

    def on_sample(self, sample: OdometrySample) -> None:
        """An encoder sample of the motion: show it, act on a deferred Ctrl-C."""
        self.progress.sample(sample)
        self.interrupts.check()

    def record(self, record: Record, state: SessionState) -> None:
        """React to one journaled record."""
        event = record.event
        if isinstance(event, MotionStart):
            opened = state.open_trial
            assert opened is not None
            assert state.plan is not None
            self.interrupts.in_motion = True
            self.progress.start(state.plan.design_of(opened.trial))
        elif isinstance(event, Solved):
            self._solved(state)
        elif isinstance(event, Void):
            self.progress.stop()
            self.console.print(f"[yellow]Trial {event.trial} attempt voided:[/] {event.reason}")
        elif isinstance(event, Finished):
            self.console.print(
                f"[bold green]Session complete:[/] {units.plural(event.n_trials or 0, 'trial')}."
            )

    def _solved(self, state: SessionState) -> None:
        """The solved pose, then the session's estimate and verdict by the one recipe."""
        trial = state.completed[-1]
        x, y, theta = trial.pose_change
        self.console.print(
            f"[green]Trial {trial.trial} solved:[/] dx={1e3 * x:+.1f} mm "
            f"dy={1e3 * y:+.1f} mm dtheta={math.degrees(theta):+.3f} deg"
            + ("" if trial.clear_cut else f" [yellow](not clear-cut: {trial.note})")
        )
        assert state.plan is not None
        outcome = final_estimate(state)
        if outcome.result is None:
            self.console.print(f"No estimate yet: {escape(outcome.problem)}", soft_wrap=True)
            return
        left = state.plan.n_trials - len(state.completed)
        self.console.print(estimate_panel(state.completed, outcome.result, left, self.system))

    def estimated(self, result: EstimateResult, state: SessionState) -> None:
        """The engine's incremental estimate: not shown (the recipe's is, at ``solved``)."""


def _fail(console: Console, check: Check) -> NoReturn:
    console.print(check_line(check))
    console.print("[red]Pre-flight failed: nothing was moved.[/]")
    raise typer.Exit(EXIT_BAD_INPUT)


@dataclass
class Opened:
    """The session the wizard works on."""

    journal: Journal
    state: SessionState


def _resume(
    console: Console,
    folder: Path,
    max_leg_m: float,
    port: str | None,
    plan_text: str | None = None,
) -> Opened:
    if plan_text is not None:
        _same_plan(console, folder, plan_text)
    try:
        resumed = resume_session(folder, {"by": "wizard", "port": port})
    except OdohilError as exc:
        _fail(console, Check("session", False, str(exc)))
    state = resumed.state
    console.print(check_line(Check("robot description", True, "the session's journaled one")))
    if resumed.torn is not None:
        console.print(f"[yellow]warning:[/] {resumed.torn.describe()}")
    assert state.plan is not None
    console.print(check_line(leg_check(state.plan, max_leg_m)))
    floor = floor_check(state.plan, description_of(state))
    if not floor.ok:
        _fail(console, floor)
    console.print(check_line(floor))
    done = len(state.completed)
    detail = f"resuming {folder}: {done} of {units.plural(state.plan.n_trials, 'trial')} done"
    console.print(check_line(Check("session", True, detail)))
    return Opened(resumed.journal, state)


def _same_plan(console: Console, folder: Path, plan_text: str) -> None:
    """A resumed session keeps its plan: a --plan that differs is refused
    (before anything is written), not silently replaced by the session's."""
    try:
        state = load_session(folder).state
        assert state.plan is not None
        given = parse_plan(plan_text, default_variant(description_of(state)))
    except OdohilError as exc:
        _fail(console, Check("session", False, str(exc)))
    if given.to_text() != state.plan.to_text():
        _fail(
            console,
            Check(
                "session",
                False,
                f"--plan {plan_text} differs from the session's plan ({state.plan.to_text()}) "
                f"in {folder}: give no --plan (or that one) to resume it, or another "
                "--session for a new session",
            ),
        )


def _prepare(
    console: Console,
    robot_file: Path | None,
    plan_text: str | None,
    max_leg_m: float,
    allow_turns: bool = False,
) -> tuple[str, Plan]:
    if robot_file is None:
        _fail(console, Check("robot description", False, "a new session needs --robot FILE"))
    try:
        text = read_robot_toml(robot_file)
        description = parse_robot_description(text, source=str(robot_file))
    except (OdohilError, OSError) as exc:
        _fail(console, Check("robot description", False, str(exc)))
    console.print(check_line(Check("robot description", True, f"{robot_file} is valid")))
    try:
        plan = check_session_plan(  # the robot's leg limits, caps; its default variant
            parse_plan(plan_text or DEFAULT_PLAN, default_variant(description)),
            description.robot.protocol,
        )
        check_turns(plan, description, allow_turns)
    except OdohilError as exc:
        _fail(console, Check("plan feasible", False, str(exc)))
    warn_turns(console, plan, description)
    checks = [
        leg_check(plan, max_leg_m),
        estimable_check(plan, description),
        floor_check(plan, description),
    ]
    for check in checks:
        if not check.ok:
            _fail(console, check)
        console.print(check_line(check))
    _check_redundancy(console, robot_file, plan)
    return text, plan


def _check_redundancy(console: Console, robot_file: Path, plan: Plan) -> None:
    """Refuse designs the description's cross distances cannot disambiguate."""
    try:
        check_redundancy(load_robot_description(robot_file), [i.design for i in plan.items])
    except OdohilError as exc:
        _fail(console, Check("cross distances", False, str(exc)))
    console.print(check_line(Check("cross distances", True, "enough for every design")))


def _start(
    console: Console, folder: Path, text: str, plan: Plan, robot_file: Path, line: Line
) -> Opened:
    try:
        journal, state = start_session(
            folder,
            text,
            plan,
            measure=OPERATOR,
            settings=line.to_json(),
            robot_path=str(robot_file),
        )
    except OdohilError as exc:
        _fail(console, Check("session", False, str(exc)))
    console.print(check_line(Check("session", True, f"new session in {folder}")))
    return Opened(journal, state)


def _line(
    console: Console,
    description: RobotDescription,
    port: str | None,
    baud: int | None,
    robot_path: str,
    journaled: Mapping[str, Any] | None = None,
) -> Line:
    """The connection in force (command line, journal, robot.toml [serial])."""
    try:
        return resolve_line(description, port, baud, robot_path, journaled)
    except OdohilError as exc:
        _fail(console, Check("port", False, str(exc)))


def _connect(console: Console, line: Line) -> Robot:
    try:
        register_fake_urls(line.port)
        robot = open_robot(line.protocol, line.port, line.baud, line.robot)
    except OdohilError as exc:
        _fail(console, Check("robot answers", False, f"{line.describe()}: {exc}"))
    try:
        sample = robot.odometry()
    except BaseException:
        robot.close()
        raise
    console.print(
        check_line(
            Check(
                "robot answers",
                True,
                f"{line.describe()}; encoders {pose_text(sample_pose(sample))}, "
                + ("MOVING (it will be stopped first)" if sample.moving else "standing still"),
            )
        )
    )
    return robot


def wizard(
    port: Annotated[
        str | None,
        typer.Option(
            "--port",
            help="Serial port (or pyserial URL) of the robot "
            "(default: the session's, else robot.toml \\[serial] port).",
        ),
    ] = None,
    robot_file: Annotated[
        Path | None,
        typer.Option("--robot", callback=robot_callback, help=ROBOT_HELP + " For new sessions."),
    ] = None,
    plan_text: Annotated[
        str | None,
        typer.Option("--plan", help=f'Designs and trial counts (default "{DEFAULT_PLAN}").'),
    ] = None,
    session: Annotated[
        Path | None,
        typer.Option("--session", help="Session folder; an existing one is resumed."),
    ] = None,
    baud: Annotated[
        int | None,
        typer.Option(
            "--baud",
            callback=bounded("baud"),
            help="Line speed (default: the session's, else robot.toml \\[serial] baud, "
            "else the robot's default).",
        ),
    ] = None,
    max_leg_m: Annotated[
        float,
        typer.Option(
            "--max-leg-m",
            callback=bounded("max_leg_m"),
            help="Longest leg the floor allows, m (the same option as plan's).",
        ),
    ] = DEFAULT_MAX_LEG_M,
    units_choice: UnitsOption = UNITS_DEFAULT,
    allow_turns: Annotated[bool, typer.Option("--allow-turns", help=ALLOW_TURNS_HELP)] = False,
) -> None:
    """Guide a calibration session beside the robot, one trial at a time."""
    console = Console(highlight=False)
    interrupts = Interrupts(
        lambda text: os.write(2, text.encode()),
        EXIT_INTERRUPTED,
        EXIT_STOP_UNCONFIRMED,
        MAY_STILL_MOVE,
    )
    interrupts.install()
    folder = session or default_session_folder()
    console.print("[bold]Pre-flight checks[/] (nothing moves until all pass)")
    try:
        check_session_folder(folder)
    except OdohilError as exc:
        _fail(console, Check("session folder", False, str(exc)))
    with signals_raise():
        code = _guided(
            console,
            folder,
            interrupts,
            port,
            baud,
            robot_file,
            plan_text,
            max_leg_m,
            unit_system(units_choice),
            allow_turns,
        )
    if code not in (EXIT_OK, EXIT_UNTRUSTED, EXIT_STOP_UNCONFIRMED):
        console.print(
            f"Stopped. The journal is in {folder}; run the wizard again with "
            f"--session {folder} to continue."
        )
    raise typer.Exit(code)


def _guided(
    console: Console,
    folder: Path,
    interrupts: Interrupts,
    port: str | None,
    baud: int | None,
    robot_file: Path | None,
    plan_text: str | None,
    max_leg_m: float,
    system: units.UnitSystem,
    allow_turns: bool = False,
) -> int:
    """Lock the session (resume or start it), then connect, then run."""
    robot: Robot | None = None
    try:
        if journal_path(folder).exists():
            opened = _resume(console, folder, max_leg_m, port, plan_text)
            header = opened.state.header
            try:
                line = _line(
                    console,
                    description_of(opened.state),
                    port,
                    baud,
                    header.robot_path or "robot.toml",
                    header.settings,
                )
            except BaseException:
                opened.journal.close()
                raise
        else:
            text, plan = _prepare(console, robot_file, plan_text, max_leg_m, allow_turns)
            assert robot_file is not None
            description = load_robot_description(robot_file)
            line = _line(console, description, port, baud, str(robot_file))
            robot = _connect(console, line)  # pre-flight ends here: nothing written before
            try:
                opened = _start(console, folder, text, plan, robot_file, line)
            except BaseException:
                robot.close()
                raise
        with opened.journal:
            if robot is None:
                robot = _connect(console, line)
            interrupts.robot = robot
            with robot:
                return _run(console, opened, robot, interrupts, line, system)
    except KeyboardInterrupt as exc:
        return exit_for_signal(signal_of(exc))


def _run(
    console: Console,
    opened: Opened,
    robot: Robot,
    interrupts: Interrupts,
    line: Line,
    system: units.UnitSystem,
) -> int:
    description = description_of(opened.state)
    progress = MotionProgress(console)
    prompts = WizardPrompts(console, description, interrupts, progress)
    observer = WizardObserver(console, interrupts, progress, system)
    engine = SessionEngine(
        opened.journal,
        opened.state,
        robot,
        OperatorSource(prompts),
        estimator=IncrementalLiveEstimator(),
        observer=observer,
        connection=line.to_json(),
        on_sample=observer.on_sample,
        start_check=prompts.start_check(robot),
    )
    try:
        engine.run()
    except StopUnconfirmedError:
        progress.stop()
        console.print(f"\n[bold red]WARNING: {MAY_STILL_MOVE}[/]", soft_wrap=True)
        report_stop(console, engine.stop_outcome, opened.journal.folder, _again(opened))
        return EXIT_STOP_UNCONFIRMED
    except KeyboardInterrupt as exc:
        progress.stop()
        console.print(f"\n[yellow]Interrupted[/] ({interrupt_text(exc)})", soft_wrap=True)
        report_stop(console, engine.stop_outcome, opened.journal.folder, _again(opened))
        return exit_for_signal(signal_of(exc))
    except OdohilError as exc:
        progress.stop()
        console.print(f"[red]error:[/] {escape(str(exc))}", soft_wrap=True)
        report_stop(console, engine.stop_outcome, opened.journal.folder, _again(opened))
        return EXIT_ERROR
    finally:
        progress.stop()
    return final_screen(console, engine.state)


def _again(opened: Opened) -> str:
    """The command that continues a wizard session (``odohil resume`` refuses them)."""
    return f"odohil wizard --session {opened.journal.folder}"


def final_screen(console: Console, state: SessionState) -> int:
    """The wizard's last words: the session's verdict by the one recipe
    (odohil/session/outcome.py), why it may not be exported, and the exit status."""
    outcome = final_estimate(state)
    console.print(outcome_line(outcome), soft_wrap=True, markup=False)
    for line in export_refusal_lines(outcome):
        console.print(line, soft_wrap=True, markup=False)
    return exit_for_outcome(outcome)


def register(app: typer.Typer) -> None:
    """Add ``wizard`` to the ``odohil`` app."""
    app.command("wizard")(wizard)
