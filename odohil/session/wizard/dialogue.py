"""The wizard's dialogue with the operator beside the robot: what is said and
asked when, decided here and shown by an :class:`OperatorScreen` (the wizard's
console, odohil/cli/wizard.py), which only renders lines and reads replies.

:class:`OperatorDialogue` is the tape's
:class:`~odohil.session.measure.tape.distances.OperatorPrompts`:
a trial's header once per attempt (on a resumed one also what was entered),
the marks to make, each distance (checked and re-asked with the reason by
odohil/session/wizard/tape_entry.py), which distances a rejection names for measuring
again, the slip check's and the ambiguity's questions, and the start check
(put the robot back, or start where it stands). :class:`OperatorWatch` sees
the session unfold: the motion bar, a voided attempt, the solved pose, then
the live estimate by the one recipe (odohil/session/run), or a guided
validation's test so far. The words are odohil/session/text/operator.py's;
each line is a :class:`~odohil.session.text.run.Said`, its tone the screen's
to render. Also which session the wizard guides (:func:`wizard_spec`) and
the command that continues it (:func:`continue_with`)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Protocol

from odohil import units
from odohil.driver.odometry import OdometrySample
from odohil.errors import InconsistentMeasurementError, MeasurementError, ParameterError
from odohil.science.estimators import EstimateResult
from odohil.science.paths import Drivable
from odohil.science.robot_description import RobotDescription
from odohil.session.journal.events import OPERATOR, Finished, MotionStart, Solved, Void
from odohil.session.journal.file import Record
from odohil.session.journal.state import CompletedTrial, SessionState
from odohil.session.measure.tape.distances import OperatorSource
from odohil.session.measure.tape.records import TapeContext
from odohil.session.measure.tape.source import TapeSource
from odohil.session.robots.protocol import Robot
from odohil.session.run import (
    Opened,
    RunOutcome,
    SessionSpec,
    default_session_folder,
    final_estimate,
    run_session,
)
from odohil.session.run.engine import StartCheck
from odohil.session.run.start_pose import StartPose, put_back
from odohil.session.text.operator import (
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
from odohil.session.text.run import Said, Tone
from odohil.session.wizard.interrupts import Interrupts
from odohil.session.wizard.tape_entry import INSTRUCTIONS, Reply, TapeEntries, parse_optional_metres
from odohil.session.wizard.validate import (
    GuidedValidation,
    guided_validation,
    validation_target,
)

__all__ = [
    "WIZARD_PLAN",
    "continue_with",
    "guided_run",
    "wizard_spec",
]

WIZARD_PLAN = "k=1,l=6,n=30;k=20,l=0.5,n=30"
"""The plan of a new wizard session given no ``--plan``."""


class OperatorScreen(Protocol):
    """What the operator sees and types (implemented by the wizard's console)."""

    def ask(self, prompt: Said) -> str:
        """Show ``prompt`` (no line end) and return the line typed; EOFError
        when the input ended."""
        ...

    def say(self, *said: Said, wrap: bool = True) -> None:
        """Show lines (``wrap``: at the screen's width, else left to the terminal)."""
        ...

    def motion(self, design: Drivable | None) -> None:
        """Show the motion bar of ``design`` (a new motion); None closes it."""
        ...

    def motion_sample(self, sample: OdometrySample) -> None:
        """An encoder sample of the motion shown."""
        ...

    def estimate(
        self, trials: Sequence[CompletedTrial], result: EstimateResult, remaining: int
    ) -> None:
        """The live estimate after a solved trial, ``remaining`` trials still planned."""
        ...


_REPLY_TONES: dict[str, tuple[Tone, str]] = {
    "refused": ("error", "refused:"),
    "check": ("note", "check:"),
}
"""How a tape entry's reply is said: the tone and head of its kind (a
``no_back`` reply is a note as a whole, the others plain)."""


def _reply_said(reply: Reply) -> Said:
    if reply.kind in _REPLY_TONES:
        tone, head = _REPLY_TONES[reply.kind]
        return Said(tone, head, f" {reply.message}")
    return Said("note" if reply.kind == "no_back" else "plain", reply.message)


@dataclass
class OperatorDialogue:
    """The wizard's :class:`~odohil.session.measure.tape.distances.OperatorPrompts`: what the
    operator is asked, on ``screen``; ``interrupts`` learns when a motion is over."""

    screen: OperatorScreen
    description: RobotDescription
    interrupts: Interrupts
    entries: TapeEntries = field(init=False)

    def __post_init__(self) -> None:
        self.entries = TapeEntries(self.description)

    def _input(self, prompt: str, tone: Tone = "plain") -> str:
        try:
            return self.screen.ask(Said(tone, prompt))
        except EOFError:
            raise MeasurementError("the input ended (no operator at the terminal)") from None

    def _context(self, ctx: TapeContext, resumed: bool = True) -> None:
        """The trial's header once per attempt; on a resumed one also what was entered."""
        if not self.entries.first_sight(ctx):
            return
        self.screen.say(Said("title", "\n" + trial_header(ctx, resumed)))
        if resumed and (entered := entered_so_far(ctx)) is not None:
            self.screen.say(Said("plain", entered))

    def confirm_start_marks(self, ctx: TapeContext) -> None:
        """Ask for the start marks."""
        self._context(ctx, resumed=False)
        self._input(start_marks(self.description))

    def confirm_end_marks(self, ctx: TapeContext) -> None:
        """The motion is over: ask for the end marks."""
        self.screen.motion(None)
        self.interrupts.in_motion = False
        self.interrupts.check()
        self._context(ctx)
        if (pose := ctx.encoder_end_pose) is not None:
            self.screen.say(Said("plain", encoders_at_end(pose)))
        self._input(END_MARKS)

    def ask_distance(self, ctx: TapeContext, index: int) -> float:
        """Distance ``index``, metres, as the attempt's :class:`TapeEntry` hands it over."""
        self._context(ctx)
        entry, new = self.entries.entry(ctx)
        if new:
            self.screen.say(Said("plain", INSTRUCTIONS))
        while (value := entry.take(index)) is None:
            reply = entry.feed(self._input(entry.question().prompt))
            if reply.message:
                self.screen.say(_reply_said(reply))
        if index in entry.kept:
            self.screen.say(Said("plain", f"{ctx.labels[index]}: {value:.4f} m kept"))
        return value

    def _optional(self, ctx: TapeContext, doubt: Said, prompt: str, label: str) -> float | None:
        self._context(ctx)
        self.screen.say(doubt)
        while True:
            try:
                return parse_optional_metres(self._input(prompt), label)
            except MeasurementError as exc:
                self.screen.say(Said("error", "refused:", f" {exc}; type it again"))

    def ask_remeasure(self, ctx: TapeContext, index: int, reason: str) -> float | None:
        """The slip check doubts the trial: ask for the suspect distance again."""
        doubt = Said("note", "check the marks:", f" {reason}")
        return self._optional(ctx, doubt, remeasure_prompt(ctx, index), ctx.labels[index])

    def ask_extra_distance(self, ctx: TapeContext, label: str, reason: str) -> float | None:
        """The trial is ambiguous: ask for one more cross distance, named by its screws."""
        doubt = Said("note", "two poses fit these marks:", f" {reason}")
        return self._optional(ctx, doubt, extra_distance_prompt(label), label)

    def start_check(self, robot: Robot) -> StartCheck:
        """Show where the robot stands; off the next trial's start, ask the
        operator to put it back there (or type 'here'), then zero the encoders there."""

        def check(start: StartPose) -> None:
            self.screen.say(Said("plain", f"Robot: {start.describe()}"))
            if not (start.ok or start.expected is None):
                reply = self._input(put_back_prompt(start.trial), "title")
                self.screen.say(Said("plain", put_back(start, reply, robot)))

        return check

    def show_rejection(self, ctx: TapeContext, rejection: InconsistentMeasurementError) -> None:
        """Say why; only the distances the rejection names are asked for again."""
        again = measure_again(ctx, self.entries.rejected(ctx, rejection))
        head = "These distances fit no rigid motion:"
        self.screen.say(Said("error", head, f" {rejection}\n{again}"))


@dataclass
class OperatorWatch:
    """Sees the session unfold for the operator: the motion bar, a voided
    attempt, the solved pose and the live estimate by the one recipe (a
    guided ``validation``: its test so far instead)."""

    screen: OperatorScreen
    interrupts: Interrupts
    validation: GuidedValidation | None = None

    def on_sample(self, sample: OdometrySample) -> None:
        """An encoder sample of the motion: show it, act on a deferred Ctrl-C."""
        self.screen.motion_sample(sample)
        self.interrupts.check()

    def record(self, record: Record, state: SessionState) -> None:
        """React to one journaled record."""
        event = record.event
        if isinstance(event, MotionStart):
            opened = state.open_trial
            assert opened is not None
            assert state.plan is not None
            self.interrupts.in_motion = True
            self.screen.motion(state.plan.design_of(opened.trial))
        elif isinstance(event, Solved):
            self._solved(state)
        elif isinstance(event, Void):
            self.screen.motion(None)
            head = f"Trial {event.trial} attempt voided:"
            self.screen.say(Said("note", head, f" {event.reason}"))
        elif isinstance(event, Finished):
            trials = units.plural(event.n_trials or 0, "trial")
            self.screen.say(Said("done", "Session complete:", f" {trials}."))

    def _solved(self, state: SessionState) -> None:
        """The solved pose, then the session's estimate and verdict by the one recipe."""
        self.screen.say(Said("good", solved(state.completed[-1])))
        assert state.plan is not None
        if self.validation is not None:  # the test so far, not an estimate
            self.screen.say(Said("plain", self.validation.live_line(state)))
            return
        outcome = final_estimate(state)
        if outcome.result is None:
            self.screen.say(Said("plain", f"No estimate yet: {outcome.problem}"), wrap=False)
            return
        left = state.plan.n_trials - len(state.completed)
        self.screen.estimate(state.completed, outcome.result, left)

    def estimated(self, result: EstimateResult, state: SessionState) -> None:
        """The engine's incremental estimate: not shown (the recipe's is, at ``solved``)."""


def guided_run(
    opened: Opened,
    screen: OperatorScreen,
    interrupts: Interrupts,
    validation: GuidedValidation | None = None,
) -> RunOutcome:
    """Run the opened session with the operator's tape: the prompts and
    screens of :class:`OperatorDialogue` and :class:`OperatorWatch` on ``screen``."""
    dialogue = OperatorDialogue(screen, opened.prepared.description, interrupts)
    watch = OperatorWatch(screen, interrupts, validation)
    try:
        return run_session(
            opened,
            watch,
            source=TapeSource(OperatorSource(dialogue), dialogue.description),
            on_sample=watch.on_sample,
            start_check=dialogue.start_check(opened.robot),
        )
    finally:
        screen.motion(None)


def continue_with(opened: Opened, validation: GuidedValidation | None) -> str:
    """The command that continues a wizard session (``odohil resume`` refuses them)."""
    if validation is not None:
        return validation.again
    return f"odohil wizard --session {opened.journal.folder}"


def wizard_spec(
    session: Path | None,
    robot_file: Path | None,
    plan: str | None,
    port: str | None,
    baud: int | None,
    max_leg_m: float,
    allow_turns: bool,
    validate: Path | None,
    path_text: str | None,
    trials: int | None,
    detect: str | None = None,
) -> tuple[SessionSpec, GuidedValidation | None]:
    """The session the wizard guides, measured with the operator's tape: a
    calibration, new or continued in ``session`` (default
    ``odohil-session-<time>`` here; ``plan`` else :data:`WIZARD_PLAN`, few
    trials a design allowed); or, with ``validate`` (``--validate SESSION
    --path PATH``, or a validation session ``session`` continues), a guided
    validation of that calibration and the validation's spec (``detect``:
    ``--detect``, the error its trial count is sized to catch).

    Raises:
        ParameterError, JournalError, RobotDescriptionError: a validation
            that cannot be guided (:func:`~odohil.session.wizard.validate.guided_validation`).
    """
    note = {"by": "wizard", "port": port}
    target = validation_target(validate, path_text, trials, session)
    if target is None and detect is not None:
        raise ParameterError("--detect sizes a validation: give --validate SESSION --path PATH too")
    if target is not None:
        guide = guided_validation(
            *target,
            trials,
            folder=session,
            robot_file=robot_file,
            port=port,
            baud=baud,
            max_leg_m=max_leg_m,
            note=note,
            detect=detect,
        )
        return guide.spec, guide
    spec = SessionSpec(
        session or default_session_folder(),
        "auto",
        robot_file,
        plan=plan,
        default_plan=WIZARD_PLAN,
        measure=OPERATOR,
        port=port,
        baud=baud,
        max_leg_m=max_leg_m,
        allow_turns=allow_turns,
        allow_few_trials=True,
        note=note,
    )
    return spec, None
