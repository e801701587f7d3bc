"""The motion-capture pose change and its covariance: the transform is frame
independent, the heading wraps, and the propagated covariance matches a Monte
Carlo of the transform itself; MotionCaptureSource computes from journaled
data only (a resume measures the same)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from odohil.science.paths import Design
from odohil.session.measure.mocap import (
    MotionCaptureSource,
    PoseStream,
    pose_change_with_covariance,
)
from odohil.session.measure.mocap.still import StillPose
from odohil.session.measure.protocol import TrialContext


def _world(pose: tuple[float, float, float], rotation: float, shift: tuple[float, float]):
    c, s = math.cos(rotation), math.sin(rotation)
    x, y, theta = pose
    return (shift[0] + c * x - s * y, shift[1] + s * x + c * y, theta + rotation)


@pytest.mark.parametrize(("rotation", "shift"), [(0.0, (0.0, 0.0)), (2.5, (3.0, -7.0))])
def test_the_change_is_the_end_in_the_start_frame_whatever_the_world_frame(
    rotation: float, shift: tuple[float, float]
) -> None:
    start, end = (0.0, 0.0, 0.0), (1.2, -0.3, 0.1)
    moved = (2.0, 1.0, math.pi / 2)  # the robot's own start, away from the origin
    start_w = _world(moved, rotation, shift)
    # end = moved composed with the change (1.2, -0.3, 0.1)
    end_local = (
        moved[0] + math.cos(moved[2]) * end[0] - math.sin(moved[2]) * end[1],
        moved[1] + math.sin(moved[2]) * end[0] + math.cos(moved[2]) * end[1],
        moved[2] + end[2],
    )
    end_w = _world(end_local, rotation, shift)
    change, _ = pose_change_with_covariance(start_w, end_w, np.eye(3), np.eye(3))
    assert change == pytest.approx((1.2, -0.3, 0.1), abs=1e-12)
    assert pose_change_with_covariance(start_w, start_w, np.eye(3), np.eye(3))[0] == (
        pytest.approx((0.0, 0.0, 0.0), abs=1e-12)
    )
    del start


def test_the_heading_change_wraps_across_pi() -> None:
    change, _ = pose_change_with_covariance(
        (0.0, 0.0, 3.1), (0.0, 0.0, -3.1), np.zeros((3, 3)), np.zeros((3, 3))
    )
    assert change[2] == pytest.approx(2 * math.pi - 6.2)


def test_the_covariance_matches_a_monte_carlo_of_the_transform() -> None:
    rng = np.random.default_rng(7)
    start = (1.0, -2.0, 2.2)
    end = (-0.4, -0.1, 2.9)  # 2.1 m away, 0.7 rad turned
    c0 = np.diag([0.002, 0.001, 0.004]) ** 2  # unequal x, y: world axes matter
    c1 = np.diag([0.001, 0.003, 0.002]) ** 2
    c1[0, 1] = c1[1, 0] = 0.5 * 0.001 * 0.003  # and a correlated pose
    _, formula = pose_change_with_covariance(start, end, c0, c1)
    n = 20_000
    e0 = rng.multivariate_normal(np.zeros(3), c0, n)
    e1 = rng.multivariate_normal(np.zeros(3), c1, n)
    draws = np.array(
        [
            pose_change_with_covariance(np.add(start, a), np.add(end, b), c0, c1)[0]
            for a, b in zip(e0, e1, strict=True)
        ]
    )
    empirical = np.cov(draws.T)
    sd = np.sqrt(np.diag(formula))
    # standard error of each sample (co)variance: sqrt((s_ii s_jj + s_ij^2) / n)
    se = np.sqrt((np.outer(sd, sd) ** 2 + formula**2) / n)
    assert np.all(np.abs(empirical - formula) < 5 * se), (empirical, formula, se)
    # and the neglected second-order terms do not show in the mean either
    exact, _ = pose_change_with_covariance(start, end, c0, c1)
    assert np.all(np.abs(draws.mean(axis=0) - exact) < 5 * sd / math.sqrt(n))


def _ctx(start: dict[str, object], end: dict[str, object]) -> TrialContext:
    return TrialContext(trial=3, attempt=1, n_trials=5, design=Design(1, 1.0), start=start, end=end)


def test_the_source_measures_from_the_journaled_still_poses_alone() -> None:
    sigma = (0.0005, 0.0007, 0.001)
    start = StillPose((2.0, 1.0, 3.0), 50, (0, 0, 0), (0.0, 0.5), 0).to_json()
    end = StillPose((1.0, 1.2, -3.0), 50, (0, 0, 0), (4.0, 4.5), 2).to_json()
    # the stream is never opened: a resumed session's source needs only ctx
    source = MotionCaptureSource(PoseStream("tcp://127.0.0.1:9"), sigma)
    measured = source.pose_change(_ctx(start, end), lambda kind, data: None)
    c = np.diag(np.square(sigma))
    change, cov = pose_change_with_covariance((2.0, 1.0, 3.0), (1.0, 1.2, -3.0), c, c)
    assert measured.pose == change
    assert np.array(measured.covariance) == pytest.approx(cov)
    assert measured.pose[2] == pytest.approx(2 * math.pi - 6.0)
    assert not measured.flagged
    assert measured.note == ""  # a clear-cut pose: no doubt to note
    assert measured.details == {
        "source": "motion capture tcp://127.0.0.1:9: still poses of 50 and 50 frames"
    }


def test_a_missing_still_pose_is_a_measurement_error() -> None:
    source = MotionCaptureSource(PoseStream("tcp://127.0.0.1:9"), (0.001, 0.001, 0.001))
    with pytest.raises(Exception, match="trial 3 end: no motion-capture still pose"):
        source.pose_change(_ctx({"pose": [0, 0, 0]}, {}), lambda kind, data: None)
