"""What the CLI used to decide itself and now asks the session layer for
(issue 18, third round; tests/session/test_cli_slim2.py for the second), in
process: the wizard's dialogue with the operator (odohil/session/operator_dialogue.py)
on a scripted screen: the trial's header once per attempt, a refused reply
and the instructions, which distances a rejection asks for again, the slip
check's question, the put-back of the start check; and what the operator sees
of the session unfolding."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import pytest

from odohil.driver.odometry import OdometrySample
from odohil.errors import InconsistentMeasurementError, MeasurementError
from odohil.science.estimators import EstimateResult
from odohil.science.floor_marks import distance_labels
from odohil.science.paths import Drivable
from odohil.session.events import Void, encode
from odohil.session.interrupts import Interrupts
from odohil.session.journal import Record
from odohil.session.operator_dialogue import OperatorDialogue, OperatorWatch
from odohil.session.operator_words import HERE
from odohil.session.plan import parse_plan
from odohil.session.run_text import Said
from odohil.session.start_pose import StartPose
from odohil.session.state import CompletedTrial
from odohil.session.tape_entry import INSTRUCTIONS
from odohil.session.tape_records import TapeContext, TapeReadings
from tests.session.helpers import description

DESIGN = parse_plan("k=1,l=1,n=2", "reverse").items[0].design
LABELS = distance_labels(description())


@dataclass
class Screen:
    """An :class:`~odohil.session.operator_dialogue.OperatorScreen` that answers
    from ``replies`` and keeps what was said (EOFError when no reply is left)."""

    replies: list[str]
    said: list[Said] = field(default_factory=list)
    asked: list[Said] = field(default_factory=list)
    motions: list[Drivable | None] = field(default_factory=list)

    def ask(self, prompt: Said) -> str:
        self.asked.append(prompt)
        if not self.replies:
            raise EOFError
        return self.replies.pop(0)

    def say(self, *said: Said, wrap: bool = True) -> None:
        self.said.extend(said)

    def motion(self, design: Drivable | None) -> None:
        self.motions.append(design)

    def motion_sample(self, sample: OdometrySample) -> None:
        """Not used here."""

    def estimate(
        self, trials: Sequence[CompletedTrial], result: EstimateResult, remaining: int
    ) -> None:
        """Not used here."""


def _ctx(**changes: object) -> TapeContext:
    ctx = TapeContext(1, 1, 2, DESIGN, encoder_end_pose=(0.0, 0.0, 0.0), labels=LABELS)
    return replace(ctx, **changes)  # type: ignore[arg-type]


def _dialogue(*replies: str) -> tuple[OperatorDialogue, Screen]:
    screen = Screen(list(replies))
    interrupts = Interrupts(print, 130, 4, "the robot may still be moving")
    return OperatorDialogue(screen, description(), interrupts), screen


def test_a_distance_refused_then_checked_then_kept_after_the_header_and_instructions() -> None:
    dialogue, screen = _dialogue("abc", "0.5", "0.5", "0.05")
    assert dialogue.ask_distance(_ctx(), 0) == pytest.approx(0.5)  # held until d2 is typed
    header, instructions, refused, check = screen.said
    assert header.tone == "title"
    assert header.head.startswith("\nTrial 1/2 (attempt 1): ")
    assert instructions == Said("plain", INSTRUCTIONS)
    assert (refused.tone, refused.head) == ("error", "refused:")
    not_metres = "'abc' is not a number of metres (e.g. 0.012, 12 mm or 1.2 cm)"
    assert refused.text == f" {not_metres}; type it again"
    assert (check.tone, check.head) == ("note", "check:")
    assert "outside the expected range" in check.text
    assert screen.asked[0].head.startswith(f"Trial 1/2, {LABELS[0]}, metres (expected ")
    assert screen.asked[-1].head.startswith(f"Trial 1/2, {LABELS[1]}, metres (expected ")
    assert len(screen.asked) == 4


def test_a_rejection_asks_again_only_for_what_it_names() -> None:
    dialogue, screen = _dialogue()
    ctx = _ctx(readings=TapeReadings(measurements=(0.1, 0.2, 0.3, 0.4, 0.5)))
    dialogue.show_rejection(ctx, InconsistentMeasurementError("d2 is off", (LABELS[1],)))
    (said,) = screen.said  # no header: the attempt's distances were asked before
    assert (said.tone, said.head) == ("error", "These distances fit no rigid motion:")
    kept = "(the other distances are kept)."
    assert said.text == f" d2 is off\nMeasure again only {LABELS[1]} {kept}"
    everything = InconsistentMeasurementError("off", ())
    dialogue.show_rejection(ctx, everything)
    assert screen.said[-1].text.endswith("Measure again all its distances.")


def test_the_slip_checks_question_keeps_the_value_on_enter_and_refuses_words() -> None:
    dialogue, screen = _dialogue("twelve", "")
    ctx = _ctx(readings=TapeReadings(measurements=(0.1, 0.2, 0.3, 0.4, 0.5)))
    assert dialogue.ask_remeasure(ctx, 1, "d2 looks like a slip") is None
    header, entered, doubt, refused = screen.said
    assert "(resumed: the motion is done" in header.head
    assert entered.head.startswith(f"Already entered and saved: {LABELS[0]} = 0.1000 m")
    assert doubt == Said("note", "check the marks:", " d2 looks like a slip")
    assert (refused.head, refused.text.endswith("; type it again")) == ("refused:", True)
    assert screen.asked[0].head.startswith(f"Re-measure {LABELS[1]}, metres (you typed 0.2000")


def test_the_end_of_input_is_a_measurement_error() -> None:
    dialogue, _ = _dialogue()
    with pytest.raises(MeasurementError, match="the input ended"):
        dialogue.confirm_start_marks(_ctx())


def test_the_end_marks_close_the_motion_bar_and_show_the_encoders() -> None:
    dialogue, screen = _dialogue("")
    dialogue.interrupts.in_motion = True
    dialogue.confirm_end_marks(_ctx(encoder_end_pose=(1.0, 0.0, 0.0)))
    assert screen.motions == [None]
    assert not dialogue.interrupts.in_motion
    assert screen.said[-1].head.startswith("Motion done; encoders say x=+1.0000 m")


class _Robot:
    """Records where its encoders were zeroed (the start check's put-back)."""

    def __init__(self) -> None:
        self.zeroed: list[tuple[float, float, float]] = []

    def zero(self, pose: tuple[float, float, float]) -> None:
        self.zeroed.append(pose)


@pytest.mark.parametrize(("reply", "zeroed"), [("", True), (HERE, False)])
def test_a_robot_off_its_start_is_put_back_or_starts_here(reply: str, zeroed: bool) -> None:
    dialogue, screen = _dialogue(reply)
    robot = _Robot()
    start = StartPose(2, (0.5, 0.0, 0.0), (0.0, 0.0, 0.0))
    dialogue.start_check(robot)(start)  # type: ignore[arg-type]
    assert screen.asked[0].tone == "title"
    assert robot.zeroed == ([(0.5, 0.0, 0.0)] if zeroed else [])  # the trial's start


def test_a_voided_attempt_closes_the_bar_and_says_why() -> None:
    screen = Screen([])
    watch = OperatorWatch(screen, Interrupts(print, 130, 4, "may still be moving"))
    kind, data = encode(Void(trial=3, attempt=1, reason="the robot did not answer"))
    record = Record(1, kind, 0.0, data)
    watch.record(record, None)  # type: ignore[arg-type]
    assert screen.motions == [None]
    assert screen.said == [Said("note", "Trial 3 attempt voided:", " the robot did not answer")]
