"""The per-trial check of a measured pose change (odohil/session/measure/plausibility.py,
odohil/science/pose_selection.py's pose_check), issue 17: a frozen stream, a
unit error and a wrong rigid body are refused with their likely cause; clean
measurements drawn from the prediction are kept, flagged about as rarely as
the slip check's level."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from odohil.science.floor_marks import PosePrior
from odohil.science.paths import Design
from odohil.science.pose_selection import (
    SLIP_LEVEL,
    ParameterBelief,
    predictive_pose,
)
from odohil.science.robot_description import ParameterPriors
from odohil.session.measure.plausibility import judge
from odohil.session.measure.protocol import MeasuredPose, Pose
from odohil.session.plans.plan import parse_plan

POSE_SIGMA = np.array([0.0005, 0.0005, 0.001])
"""A still pose's standard deviations: the pose change's are about sqrt 2 times."""
ONE_WAY = parse_plan("k=0.5,l=2,n=1").design_of(1)
CLOSED = parse_plan("k=1,l=1,n=1").design_of(1)


def _predicted(design: Design, encoders: Pose) -> PosePrior:
    return predictive_pose(design, ParameterBelief.from_priors(ParameterPriors()), encoders)


def _measured(pose: Pose, excursion_m: float | None = None, **kw: Any) -> MeasuredPose:
    c = 2.0 * POSE_SIGMA**2
    return MeasuredPose(
        pose=pose,
        covariance=((c[0], 0.0, 0.0), (0.0, c[1], 0.0), (0.0, 0.0, c[2])),
        details={"source": "motion capture tcp://capture:5555"},
        excursion_m=excursion_m,
        **kw,
    )


ONE_WAY_ENCODERS: Pose = (2.0012, 0.0, 0.0)
ONE_WAY_TRUE: Pose = (1.98, -0.009, -0.0092)
"""What a 2 m one-way trial's encoders say, and a true pose change it plausibly made."""


def test_a_plausible_one_way_trial_is_kept_with_the_checks_numbers() -> None:
    judged = judge(
        1, _measured(ONE_WAY_TRUE), _predicted(ONE_WAY, ONE_WAY_ENCODERS), ONE_WAY_ENCODERS
    )
    assert judged.refusal == ""
    assert not judged.measured.flagged
    check = judged.measured.details["check"]
    assert check["T"] < check["limit"]
    assert check["displacement_m"] == pytest.approx(np.hypot(*ONE_WAY_TRUE[:2]))
    assert check["encoder_displacement_m"] == pytest.approx(2.0012)


def test_a_frozen_stream_on_a_one_way_trial_is_refused_naming_it() -> None:
    frozen: Pose = (0.0003, -0.0002, 0.0009)
    judged = judge(3, _measured(frozen), _predicted(ONE_WAY, ONE_WAY_ENCODERS), ONE_WAY_ENCODERS)
    assert judged.refusal.startswith(
        "trial 3: the measured pose change is implausible: displacement 0.000 m where the "
        "encoders say 2.001 m: frozen stream?"
    )
    assert "motion capture tcp://capture:5555" in judged.refusal


@pytest.mark.parametrize(
    ("factor", "unit"),
    [(1000.0, "millimetres?"), (100.0, "centimetres?"), (1 / 0.0254, "inches?")],
)
def test_a_unit_error_is_refused_naming_the_unit(factor: float, unit: str) -> None:
    x, y, theta = ONE_WAY_TRUE
    scaled: Pose = (x * factor, y * factor, theta)  # the heading stays in radians
    judged = judge(1, _measured(scaled), _predicted(ONE_WAY, ONE_WAY_ENCODERS), ONE_WAY_ENCODERS)
    assert f"where the encoders say 2.001 m: {unit}" in judged.refusal


def test_millimetres_on_a_closed_trial_are_named_from_the_pose_alone() -> None:
    encoders: Pose = (0.0008, 0.0, 0.0)  # back at the start, by the encoders
    true: Pose = (-0.012, 0.008, -0.016)  # a centimetre off, as odometry drifts
    scaled: Pose = (1000 * true[0], 1000 * true[1], true[2])
    judged = judge(1, _measured(scaled), _predicted(CLOSED, encoders), encoders)
    assert "millimetres? (its distances divided by 1000 it fits" in judged.refusal


def test_a_heading_in_degrees_is_named() -> None:
    encoders: Pose = (0.0008, 0.0, 0.0)
    true: Pose = (-0.012, 0.008, -0.016)
    in_degrees: Pose = (true[0], true[1], float(np.degrees(true[2])))
    judged = judge(1, _measured(in_degrees), _predicted(CLOSED, encoders), encoders)
    assert ": theta in degrees? (as radians it fits" in judged.refusal


def test_a_frozen_stream_on_a_closed_trial_is_told_by_the_path_it_saw() -> None:
    encoders: Pose = (0.0008, 0.0, 0.0)
    trajectory = [
        (0.0, 0.0, 0.0, 0.0),
        (2.0, 1.0004, 0.0, 0.0),
        (9.0, 1.0004, 0.0, 3.14),
        (11.0, 0.0008, 0.0, 0.0),
    ]
    still: Pose = (0.0004, 0.0003, -0.0005)  # the closed trial's end: plausible by itself
    predicted = _predicted(CLOSED, encoders)
    unseen = judge(1, _measured(still), predicted, encoders, trajectory)
    assert unseen.refusal == ""  # a stream that did not see the path cannot tell
    frozen = judge(1, _measured(still, excursion_m=0.003), predicted, encoders, trajectory)
    assert "excursion 0.003 m where the encoders say 1.000 m: frozen stream?" in frozen.refusal
    seen = judge(1, _measured(still, excursion_m=1.004), predicted, encoders, trajectory)
    assert seen.refusal == ""
    assert seen.measured.details["check"]["excursion_m"] == 1.004
    in_mm = judge(1, _measured(still, excursion_m=1001.2), predicted, encoders, trajectory)
    assert "excursion 1001.200 m where the encoders say 1.000 m: millimetres?" in in_mm.refusal


def test_a_wrong_rigid_body_is_refused() -> None:
    other: Pose = (0.4, 1.1, 0.9)  # another robot, driving its own path
    judged = judge(1, _measured(other), _predicted(ONE_WAY, ONE_WAY_ENCODERS), ONE_WAY_ENCODERS)
    assert "where the encoders say 2.001 m: a wrong rigid body" in judged.refusal


def test_clean_measurements_are_kept_and_flagged_about_as_rarely_as_the_slip_level() -> None:
    predicted = _predicted(ONE_WAY, ONE_WAY_ENCODERS)
    measurement_cov = np.diag(2.0 * POSE_SIGMA**2)
    rng = np.random.default_rng(17)
    n = 1000
    draws = rng.multivariate_normal(predicted.mean, predicted.cov + measurement_cov, n)
    flagged = 0
    for draw in draws:
        pose: Pose = (float(draw[0]), float(draw[1]), float(draw[2]))
        judged = judge(1, _measured(pose), predicted, ONE_WAY_ENCODERS)
        assert judged.refusal == "", judged.refusal
        flagged += judged.measured.flagged
    # expected 1; P(more than 6 | Poisson 1) < 1e-4
    assert flagged <= 6, flagged
    assert n * SLIP_LEVEL == 1


def test_a_doubtful_pose_is_flagged_unless_its_source_checked_it_already() -> None:
    predicted = _predicted(ONE_WAY, ONE_WAY_ENCODERS)
    root = np.linalg.cholesky(predicted.cov + np.diag(2.0 * POSE_SIGMA**2))
    off = predicted.mean + root @ np.array([0.0, 6.0, 0.0])  # T = 36: doubtful, not implausible
    doubtful: Pose = (float(off[0]), float(off[1]), float(off[2]))
    judged = judge(1, _measured(doubtful), predicted, ONE_WAY_ENCODERS)
    assert judged.refusal == ""
    assert judged.measured.flagged
    assert judged.measured.flag_reason.startswith("the trial does not fit the other trials")
    taped = judge(1, _measured(doubtful, prediction_checked=True), predicted, ONE_WAY_ENCODERS)
    assert not taped.measured.flagged
    assert taped.refusal == ""


def test_a_pose_its_source_flagged_or_found_ambiguous_is_not_judged_again() -> None:
    predicted = _predicted(ONE_WAY, ONE_WAY_ENCODERS)
    frozen: Pose = (0.0, 0.0, 0.0)
    kept = _measured(frozen, flagged=True, flag_reason="the operator kept d3")
    assert judge(1, kept, predicted, ONE_WAY_ENCODERS).measured is kept
    ambiguous = _measured(frozen, ambiguous=True)
    assert judge(1, ambiguous, predicted, ONE_WAY_ENCODERS).refusal == ""
