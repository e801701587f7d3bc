"""Rests and measured pose changes (odohil/science/rest_cutting.py)."""

from __future__ import annotations

import math

import numpy as np

from odohil.science.frames import compose
from odohil.science.rest_cutting import (
    REST_SPEED_M_PER_S,
    edge_rests,
    measured_change,
    rest_windows,
    still_mask,
)


def _poses(x: np.ndarray, theta: np.ndarray | None = None) -> np.ndarray:
    theta = np.zeros_like(x) if theta is None else theta
    return np.stack([x, np.zeros_like(x), theta], axis=1)


def test_jitter_is_still_and_slow_motion_is_not() -> None:
    rng = np.random.default_rng(1)
    t = np.arange(0.0, 10.0, 0.02)
    x = np.where(t < 4, 0.0, np.where(t < 6, (t - 4) * 0.05, 0.1))
    theta = rng.normal(0, 0.003, len(t))  # 3 mrad jitter, a poor capture system
    x = x + rng.normal(0, 0.0003, len(t))
    still = still_mask(t, _poses(x, theta))
    windows = rest_windows(t, still, 1.0)
    assert len(windows) == 2
    (_, a1), (b0, _) = windows
    # the rests stop before the motion starts and start after it ends (both ways judged)
    assert t[a1] < 4.0 < 6.0 < t[b0]
    assert t[a1] > 3.5
    assert t[b0] < 6.5
    # creeping at half the still speed is still; at twice it, moving (ends included)
    slow = still_mask(t, _poses(t * REST_SPEED_M_PER_S * 0.5))
    assert slow[50:-50].all()
    fast = still_mask(t, _poses(t * REST_SPEED_M_PER_S * 2.0))
    assert not fast.any()


def test_a_missing_pose_is_not_still_nor_are_its_neighbours() -> None:
    t = np.arange(0.0, 4.0, 0.05)
    poses = _poses(np.zeros_like(t))
    poses[40] = np.nan
    still = still_mask(t, poses)
    assert not still[40]
    assert not still[38]
    assert not still[42]
    assert still[:30].all()
    assert still[50:].all()


def test_edge_rests_take_the_odometry_within_its_tolerance() -> None:
    t = np.arange(0.0, 5.0, 0.05)
    x = np.clip((t - 1.0) * 0.1, 0.0, 0.3)
    x[5] += 0.0005  # a twitch of half a millimetre inside the rest
    start, end = edge_rests(t, _poses(x), 0.2)
    assert start == (0, 20)
    assert end is not None
    assert t[end[0]] > 3.99
    assert edge_rests(t, _poses(np.zeros_like(t)), 0.2) == (None, None)
    moving = _poses(t * 0.1)
    assert edge_rests(t, moving, 0.2) == (None, None)


def test_edge_rests_at_a_heading_near_pi_are_rests() -> None:
    t = np.arange(0.0, 5.0, 0.05)
    x = np.clip((t - 1.0) * 0.1, 0.0, 0.3)
    jitter = np.where(np.arange(len(t)) % 2 == 0, 1e-4, -1e-4)
    theta = np.angle(np.exp(1j * (math.pi + jitter)))  # wrapped: jumps between +pi and -pi
    start, end = edge_rests(t, _poses(x, theta), 0.2)
    assert start is not None
    assert t[start[1]] > 0.95
    assert end is not None


def test_measured_change_is_in_the_start_frame_within_pi_of_the_encoder_turn() -> None:
    start = (2.0, -1.0, 3.0)
    change = (0.5, 0.1, 2 * math.pi + 0.2)  # a loop and a bit
    end = compose(start, change)
    end_wrapped = (end[0], end[1], math.remainder(end[2], 2 * math.pi))
    cov = np.diag([1e-8, 1e-8, 1e-6])
    pose, pose_cov = measured_change(start, end_wrapped, cov, cov, 2 * math.pi + 0.15, 2 * math.pi)
    np.testing.assert_allclose(pose, [0.5, 0.1, 0.2], atol=1e-12)
    # heading variance adds; the start heading's uncertainty moves the end sideways
    assert math.isclose(pose_cov[2, 2], 2e-6)
    assert pose_cov[1, 1] > 2e-8 + 0.5**2 * 1e-6 * 0.99
