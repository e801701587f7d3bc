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

import os
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console
from rich.markup import escape

from odohil import units
from odohil.cli.exit_codes import (
    EXIT_BAD_INPUT,
    EXIT_INTERRUPTED,
    EXIT_OK,
    EXIT_STOP_UNCONFIRMED,
    EXIT_UNTRUSTED,
    exit_for_outcome,
    exit_for_run,
    exit_for_signal,
)
from odohil.cli.options import (
    UNITS_DEFAULT,
    AllowTurnsOption,
    BaudOption,
    PortOption,
    UnitsOption,
    option,
    robot_option,
    unit_system,
)
from odohil.cli.render import (
    MotionProgress,
    bad_inputs,
    check_line,
    estimate_panel,
    print_lines,
    print_refusal,
    print_verdict,
)
from odohil.cli.session_view import prepared_or_exit, refuse, report_run
from odohil.driver.odometry import OdometrySample
from odohil.errors import InconsistentMeasurementError, MeasurementError
from odohil.science.estimators import EstimateResult
from odohil.science.planner import DEFAULT_MAX_LEG_M
from odohil.science.robot_description import RobotDescription
from odohil.session.engine import StartCheck
from odohil.session.events import Finished, MotionStart, Solved, Void
from odohil.session.interrupts import Interrupts, wait_readable
from odohil.session.journal import Record
from odohil.session.lifecycle import (
    Opened,
    PreflightCheck,
    PreflightFailed,
    SessionSpec,
    default_session_folder,
    final_estimate,
    open_session,
    preflight,
    run_session,
)
from odohil.session.operator_words import (
    END_MARKS,
    encoders_at_end,
    entered_so_far,
    extra_distance_prompt,
    measure_again,
    put_back_prompt,
    remeasure_prompt,
    solved,
    start_marks,
    trial_header,
)
from odohil.session.outcome_text import outcome_line
from odohil.session.pose_sources import OPERATOR
from odohil.session.robot import Robot
from odohil.session.run_text import MAY_STILL_MOVE
from odohil.session.signals import signal_of, signals_raise
from odohil.session.sources import OperatorSource, TapeSource
from odohil.session.start_pose import StartPose, put_back
from odohil.session.state import SessionState
from odohil.session.tape_entry import INSTRUCTIONS, TapeEntries, parse_optional_metres
from odohil.session.tape_records import TapeContext
from odohil.session.validation import PATH_SYNTAX
from odohil.session.validation_wizard import (
    GuidedValidation,
    guided_validation,
    validation_target,
)

DEFAULT_PLAN = "k=1,l=6,n=30;k=20,l=0.5,n=30"
_STYLE = {"refused": "[red]refused:[/] ", "check": "[yellow]check:[/] ", "no_back": "[yellow]"}


@dataclass
class WizardPrompts:
    """The :class:`~odohil.session.sources.OperatorPrompts` of the wizard: it reads
    lines and renders; what they mean and say is odohil/session/tape_entry.py's
    and odohil/session/operator_words.py's."""

    console: Console
    description: RobotDescription
    interrupts: Interrupts
    progress: MotionProgress

    def __post_init__(self) -> None:
        self.entries = TapeEntries(self.description)

    def _input(self, prompt: str, style: str | None = None) -> str:
        try:
            self.console.print(prompt, end="", style=style)
            wait_readable(sys.stdin)
            return input()
        except EOFError:
            raise MeasurementError("the input ended (no operator at the terminal)") from None

    def _context(self, ctx: TapeContext, resumed: bool = True) -> None:
        """The trial's header once per attempt; on a resumed one also what was entered."""
        if not self.entries.first_sight(ctx):
            return
        self.console.print("\n" + trial_header(ctx, resumed), style="bold", markup=False)
        if resumed and (entered := entered_so_far(ctx)) is not None:
            self.console.print(entered, markup=False)

    def confirm_start_marks(self, ctx: TapeContext) -> None:
        """Ask for the start marks."""
        self._context(ctx, resumed=False)
        self._input(start_marks(self.description))

    def confirm_end_marks(self, ctx: TapeContext) -> None:
        """The motion is over: ask for the end marks."""
        self.progress.stop()
        self.interrupts.in_motion = False
        self.interrupts.check()
        self._context(ctx)
        if (pose := ctx.encoder_end_pose) is not None:
            self.console.print(encoders_at_end(pose))
        self._input(END_MARKS)

    def ask_distance(self, ctx: TapeContext, index: int) -> float:
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

    def _optional(self, ctx: TapeContext, doubt: str, prompt: str, label: str) -> float | None:
        self._context(ctx)
        self.console.print(doubt)
        while True:
            try:
                return parse_optional_metres(self._input(prompt), label)
            except MeasurementError as exc:
                self.console.print(f"[red]refused:[/] {exc}; type it again")

    def ask_remeasure(self, ctx: TapeContext, index: int, reason: str) -> float | None:
        """The slip check doubts the trial: ask for the suspect distance again."""
        doubt = f"[yellow]check the marks:[/] {reason}"
        return self._optional(ctx, doubt, remeasure_prompt(ctx, index), ctx.labels[index])

    def ask_extra_distance(self, ctx: TapeContext, label: str, reason: str) -> float | None:
        """The trial is ambiguous: ask for one more cross distance, named by its screws."""
        doubt = f"[yellow]two poses fit these marks:[/] {reason}"
        return self._optional(ctx, doubt, extra_distance_prompt(label), label)

    def start_check(self, robot: Robot) -> StartCheck:
        """Show where the robot stands; off the next trial's start, ask the
        operator to put it back there (or type 'here'), then zero the encoders there."""

        def check(start: StartPose) -> None:
            self.console.print(f"Robot: {start.describe()}")
            if not (start.ok or start.expected is None):
                reply = self._input(put_back_prompt(start.trial), "bold")
                self.console.print(put_back(start, reply, robot))

        return check

    def show_rejection(self, ctx: TapeContext, rejection: InconsistentMeasurementError) -> None:
        """Say why; only the distances the rejection names are asked for again."""
        again = measure_again(ctx, self.entries.rejected(ctx, rejection))
        self.console.print(f"[red]These distances fit no rigid motion:[/] {rejection}\n{again}")


@dataclass
class WizardObserver:
    """Sees the session unfold: motion bar, solved pose, and the live estimate
    by the one recipe (odohil/session/outcome.py)."""

    console: Console
    interrupts: Interrupts
    progress: MotionProgress
    system: units.UnitSystem = units.DEFAULT_UNIT_SYSTEM
    validation: GuidedValidation | None = None

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
        self.console.print(solved(state.completed[-1]), style="green", markup=False)
        assert state.plan is not None
        if self.validation is not None:  # the test so far, not an estimate
            self.console.print(self.validation.live_line(state), markup=False)
            return
        outcome = final_estimate(state)
        if outcome.result is None:
            self.console.print(f"No estimate yet: {escape(outcome.problem)}", soft_wrap=True)
            return
        left = state.plan.n_trials - len(state.completed)
        self.console.print(estimate_panel(state.completed, outcome.result, left, self.system))

    def estimated(self, result: EstimateResult, state: SessionState) -> None:
        """The engine's incremental estimate: not shown (the recipe's is, at ``solved``)."""


def wizard(
    port: PortOption = None,
    robot_file: Annotated[Path | None, robot_option(" For new sessions.")] = None,
    plan_text: Annotated[
        str | None,
        typer.Option("--plan", help=f'Designs and trial counts (default "{DEFAULT_PLAN}").'),
    ] = None,
    session: Annotated[
        Path | None,
        typer.Option("--session", help="Session folder; an existing one is resumed."),
    ] = None,
    baud: BaudOption = None,
    max_leg_m: Annotated[
        float,
        option(
            "--max-leg-m",
            bound="max_leg_m",
            help="Longest leg the floor allows, m (the same option as plan's).",
        ),
    ] = DEFAULT_MAX_LEG_M,
    units_choice: UnitsOption = UNITS_DEFAULT,
    allow_turns: AllowTurnsOption = False,
    validate: Annotated[Path | None, typer.Option("--validate", help="Validate this calibrated "
                        "session on --path with the tape instead (journaled in "
                        "SESSION/validation/<path>/ or --session; exit 0 pass, 3 fail).")] = None,
    path_text: Annotated[str | None, option("--path", help=PATH_SYNTAX)] = None,
    trials: Annotated[int | None, option("--trials", bound="plan_n", help="Trials of --path "
                      "(a new validation).")] = None,
) -> None:  # fmt: skip
    """Guide a calibration session beside the robot, one trial at a time
    (with --validate SESSION --path PATH: a validation of it)."""
    console = Console(highlight=False)
    interrupts = Interrupts(
        lambda text: os.write(2, text.encode()),
        EXIT_INTERRUPTED,
        EXIT_STOP_UNCONFIRMED,
        MAY_STILL_MOVE,
    )
    interrupts.install()
    folder = session or default_session_folder()
    note = {"by": "wizard", "port": port}
    spec = SessionSpec(
        folder, "auto", robot_file, plan=plan_text, default_plan=DEFAULT_PLAN,
        measure=OPERATOR, port=port, baud=baud, max_leg_m=max_leg_m, allow_turns=allow_turns,
        allow_few_trials=True, note=note,
    )  # fmt: skip
    guide = None
    with bad_inputs():  # --validate, or a validation session continued by --session alone
        target = validation_target(validate, path_text, trials, session)
        if target is not None:
            guide = guided_validation(
                *target, trials, folder=session, robot_file=robot_file, port=port, baud=baud,
                max_leg_m=max_leg_m, note=note,
            )  # fmt: skip
    if guide is not None:
        spec = guide.spec
        if not guide.trusted:
            print_refusal(console, guide.calibration.outcome, None, "nothing driven")
            raise typer.Exit(EXIT_UNTRUSTED)
        print_lines(console, [outcome_line(guide.calibration.outcome)])
    console.print("[bold]Pre-flight checks[/] (nothing moves until all pass)")
    with signals_raise():
        code = _guided(console, spec, interrupts, unit_system(units_choice), guide)
    again = f"the wizard again with --session {spec.folder}" if guide is None else guide.again
    if code not in (EXIT_OK, EXIT_BAD_INPUT, EXIT_UNTRUSTED, EXIT_STOP_UNCONFIRMED):
        console.print(f"Stopped. The journal is in {spec.folder}; run {again} to continue.")
    raise typer.Exit(code)


def _guided(
    console: Console,
    spec: SessionSpec,
    interrupts: Interrupts,
    system: units.UnitSystem,
    guide: GuidedValidation | None,
) -> int:
    """Pre-flight (each check a tick), open the session (resume or start it:
    locked, connected), then run; a pre-flight failure exits by its class."""

    def tick(check: PreflightCheck) -> None:
        console.print(check_line(check))

    try:
        prepared = prepared_or_exit(preflight(spec), console, tick)
        with open_session(prepared, tick) as opened:
            if opened.torn is not None:
                console.print(f"[yellow]warning:[/] {opened.torn.describe()}")
            interrupts.robot = opened.robot
            return _run(console, opened, interrupts, system, guide)
    except PreflightFailed as exc:
        refuse(console, exc.check, tick)
    except KeyboardInterrupt as exc:
        return exit_for_signal(signal_of(exc))


def _run(
    console: Console,
    opened: Opened,
    interrupts: Interrupts,
    system: units.UnitSystem,
    guide: GuidedValidation | None,
) -> int:
    """The session with the operator's prompts and screens, to the final screen."""
    progress = MotionProgress(console)
    prompts = WizardPrompts(console, opened.prepared.description, interrupts, progress)
    observer = WizardObserver(console, interrupts, progress, system, guide)
    try:
        outcome = run_session(
            opened, observer, source=TapeSource(OperatorSource(prompts), prompts.description),
            on_sample=observer.on_sample,
            start_check=prompts.start_check(opened.robot),
        )  # fmt: skip
    finally:
        progress.stop()
    if outcome.status == "finished" and guide is not None:
        passed, lines = guide.final(outcome.state)
        print_lines(console, lines)
        return EXIT_OK if passed else EXIT_UNTRUSTED
    if outcome.status == "finished":
        return final_screen(console, outcome.state)
    # the command that continues a wizard session (`odohil resume` refuses them)
    again = f"odohil wizard --session {opened.journal.folder}" if guide is None else guide.again
    report_run(console, outcome, again, interrupted="Interrupted")
    return exit_for_run(outcome)


def final_screen(console: Console, state: SessionState) -> int:
    """The wizard's last words: the session's verdict by the one recipe
    (odohil/session/outcome.py), why it may not be exported, and the exit status."""
    outcome = final_estimate(state)
    print_verdict(console, outcome)
    return exit_for_outcome(outcome)
