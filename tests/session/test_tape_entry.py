"""The operator's entry of tape distances (odohil/session/wizard/tape_entry.py), in
process: what a typed line means, the expected ranges from the session's
prediction, typed floor-mark rejections, and the wizard's floor check of the
plan (issue 18)."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from odohil.errors import InconsistentMeasurementError, MeasurementError
from odohil.science.floor_marks import (
    MarkDistances,
    PosePrior,
    distance_labels,
    marks_from_pose,
    solve_marks,
)
from odohil.science.robot_description import parse_robot_description
from odohil.session.measure.tape.distances import OperatorSource
from odohil.session.measure.tape.records import TapeContext, TapeReadings
from odohil.session.measure.tape.source import TapeSource
from odohil.session.measure.truth import relative_true_pose
from odohil.session.plans.plan import parse_plan
from odohil.session.run.engine import IncrementalLiveEstimator, SessionEngine, start_session
from odohil.session.wizard.tape_entry import (
    ExpectedRange,
    TapeEntries,
    TapeEntry,
    attempt_ranges,
    expected_ranges,
    kept_after,
    parse_metres,
    parse_optional_metres,
)
from tests.session.helpers import FAST, ROBOT_TOML, PortTruth, description, fake_robot

DESIGN = parse_plan("k=1,l=1,n=2", "reverse").items[0].design
LABELS = distance_labels(description())
WIDE = ExpectedRange(0.0, 10.0, 20.0)


def _ctx(**changes: object) -> TapeContext:
    ctx = TapeContext(1, 1, 2, DESIGN, encoder_end_pose=(0.0, 0.0, 0.0), labels=LABELS)
    return replace(ctx, **changes)  # type: ignore[arg-type]


# --- what a line means ---------------------------------------------------------


@pytest.mark.parametrize(
    ("text", "metres"),
    [("0.012", 0.012), ("12 mm", 0.012), ("1.2cm", 0.012), (" 1.234 m ", 1.234)],
)
def test_a_typed_distance_becomes_metres(text: str, metres: float) -> None:
    assert parse_metres(text, "d1") == pytest.approx(metres, rel=1e-12)


@pytest.mark.parametrize(
    ("text", "why"),
    [("abc", "is not a number of metres"), ("-0.01", "cannot be negative"), ("nan", "finite")],
)
def test_what_is_no_distance_is_refused(text: str, why: str) -> None:
    with pytest.raises(MeasurementError, match=why):
        parse_metres(text, "d1")
    assert parse_optional_metres("  ", "d1") is None


def test_back_corrects_only_the_value_typed_just_before() -> None:
    entry = TapeEntry(("a", "b", "c"), (WIDE,) * 3)
    assert entry.take(0) is None
    assert entry.question().back_to is None
    assert entry.feed("back").kind == "no_back"
    assert entry.feed("1.0").kind == "entered"
    assert entry.take(0) is None  # held until the next distance is typed
    assert (entry.question().label, entry.question().back_to) == ("b", "a")
    assert entry.feed("-").message == "Correct a:"
    assert entry.question().label == "a"
    assert entry.feed("back").kind == "no_back"  # one step back only
    entry.feed("1.1")
    entry.feed("20 mm")
    assert entry.take(0) == 1.1
    assert entry.take(1) is None
    assert entry.question().back_to == "b"
    entry.feed("3 cm")
    assert (entry.take(1), entry.take(2)) == (0.02, pytest.approx(0.03))  # the last at once


def test_out_of_range_asks_again_and_implausible_is_refused() -> None:
    entry = TapeEntry(("a",), (ExpectedRange(0.1, 0.2, 1.0),))
    assert entry.take(0) is None
    assert entry.feed("2").kind == "refused"
    assert entry.feed("0.5").kind == "check"
    assert entry.feed("0.4").kind == "check"  # another value: asked again
    assert entry.feed("0.4").kind == "entered"  # the same again: kept
    assert entry.take(0) == 0.4


def test_distances_a_typed_rejection_did_not_name_are_kept_without_asking() -> None:
    desc = description()
    marks = marks_from_pose(desc, (1.0, 0.0, 0.0)).as_array()
    marks[0] += 0.05
    with pytest.raises(InconsistentMeasurementError) as caught:
        solve_marks(desc, MarkDistances.of(desc, marks), (1.0, 0.0, 0.0))
    assert caught.value.labels[0] == LABELS[0]
    kept = kept_after(caught.value, LABELS, tuple(marks))
    assert set(kept) == set(range(len(LABELS))) - {LABELS.index(x) for x in caught.value.labels}
    assert kept_after(InconsistentMeasurementError("named none"), LABELS, tuple(marks)) == {}
    entry = TapeEntry(LABELS, (WIDE,) * len(LABELS), kept)
    assert entry.take(1) == kept[1]
    assert entry.take(0) is None
    assert entry.question().label == LABELS[0]


def test_a_rejection_starts_a_round_that_keeps_what_it_did_not_name() -> None:
    entries = TapeEntries(description())
    first = _ctx(readings=TapeReadings(measurements=(0.1, 0.2, 0.3, 0.4, 0.5)))
    assert entries.first_sight(first)
    assert not entries.first_sight(first)
    entry, new = entries.entry(first)
    assert new
    assert entries.entry(first) == (entry, False)
    named = InconsistentMeasurementError("d2 is off", (LABELS[1],))
    assert entries.rejected(first, named) == {0: 0.1, 2: 0.3, 3: 0.4, 4: 0.5}
    second, new = entries.entry(_ctx(readings=TapeReadings(rejections=1)))
    assert new
    assert second.take(0) == 0.1
    assert second.take(1) is None
    assert second.question().prompt.startswith(f"Trial 1/2, {LABELS[1]}, metres (expected ")


# --- expected ranges ---------------------------------------------------------------


def test_the_descriptions_priors_set_the_ranges_before_any_estimate() -> None:
    other = parse_robot_description(
        ROBOT_TOML + "[priors]\nE_T = 0.05\nE_R_deg_per_m = 2.0\n", "other priors"
    )
    assert attempt_ranges(_ctx(), description()) != attempt_ranges(_ctx(), other)


def test_the_engines_prediction_sets_the_ranges() -> None:
    prior = PosePrior(mean=np.array([0.01, 0.0, 0.0]), cov=np.diag([1e-6, 1e-6, 1e-6]))
    moved = PosePrior(mean=np.array([0.03, 0.0, 0.0]), cov=prior.cov)
    assert attempt_ranges(_ctx(predicted=prior), description()) == expected_ranges(
        description(), DESIGN, prior, seed=1
    )
    assert attempt_ranges(_ctx(predicted=prior), description()) != attempt_ranges(
        _ctx(predicted=moved), description()
    )


class _Operator:
    """A perfect tape that checks each true distance against its expected range."""

    def __init__(self, truth: PortTruth) -> None:
        self.truth = truth
        self.start = self.change = (0.0, 0.0, 0.0)
        self.outside: list[tuple[int, str, float, ExpectedRange]] = []
        self.asked = 0

    def confirm_start_marks(self, ctx: TapeContext) -> None:
        self.start = self.truth.true_pose()

    def confirm_end_marks(self, ctx: TapeContext) -> None:
        winding = ctx.design.path().winding_rad
        self.change = relative_true_pose(self.start, self.truth.true_pose(), winding)

    def ask_distance(self, ctx: TapeContext, index: int) -> float:
        true = float(marks_from_pose(description(), self.change).as_array()[index])
        expected = attempt_ranges(ctx, description())[index]
        self.asked += 1
        if not expected.low <= true <= expected.high:
            self.outside.append((ctx.trial, ctx.labels[index], true, expected))
        return true

    def show_rejection(self, ctx: TapeContext, rejection: InconsistentMeasurementError) -> None:
        raise AssertionError(rejection)

    def ask_remeasure(self, ctx: TapeContext, index: int, reason: str) -> float | None:
        return None

    def ask_extra_distance(self, ctx: TapeContext, label: str, reason: str) -> float | None:
        return None


def test_the_expected_ranges_contain_the_truth_on_the_fake(tmp_path: Path) -> None:
    plan = parse_plan("k=1,l=1,n=3;k=0.5,l=1.5,n=3", "reverse")
    with fake_robot(f"seed=7&{FAST}") as (robot, truth):
        journal, state = start_session(tmp_path, ROBOT_TOML, plan, measure="operator", settings={})
        operator = _Operator(truth)
        with journal:
            final = SessionEngine(
                journal,
                state,
                robot,
                TapeSource(OperatorSource(operator), description()),
                estimator=IncrementalLiveEstimator(),
            ).run()
    assert final.finished
    assert operator.asked == 6 * len(LABELS)
    assert operator.outside == []
