"""Odometry compressed into legs and turns (odohil/science/odometry_paths.py):
the compressed path ends where the odometry ends, a circle is a few dozen
legs, turns in place are spins, and families are named right."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from odohil.science.odometry_paths import (
    HEADING_STEP_RAD,
    LEG_MAX_M,
    CompressionBounds,
    compress_odometry,
    integrate_ticks,
    odometry_end_pose,
    path_family,
)
from odohil.science.paths import Leg, Turn

END_POSE_TOLERANCE_M = 2e-9
"""1e-9 m of rounding, plus the 1 nm leg a path that never moves carries."""
END_POSE_TOLERANCE_RAD = 1e-12
PER_COUNT = math.pi * 0.084 / 2796.8  # the optiodom robot
BASE = 0.20


def _ticks_for(v: np.ndarray, w: np.ndarray, dt: float, seed: int = 0) -> np.ndarray:
    """Odometry poses from wheel counts of commanded speeds (rounded to whole counts)."""
    left = np.cumsum((v - 0.5 * BASE * w) * dt / PER_COUNT)
    right = np.cumsum((v + 0.5 * BASE * w) * dt / PER_COUNT)
    rng = np.random.default_rng(seed)
    left = np.floor(left + rng.uniform(0, 1, len(left)))
    right = np.floor(right + rng.uniform(0, 1, len(right)))
    return integrate_ticks(
        np.concatenate([[0], left]), np.concatenate([[0], right]), PER_COUNT, PER_COUNT, BASE
    )


def _assert_ends_where_odometry_ends(poses: np.ndarray, path) -> None:
    x, y, theta = path.encoder_end_pose()
    ox, oy, otheta = odometry_end_pose(poses)
    assert abs(x - ox) < END_POSE_TOLERANCE_M
    assert abs(y - oy) < END_POSE_TOLERANCE_M
    assert abs(theta - otheta) < END_POSE_TOLERANCE_RAD


def test_a_two_lap_circle_becomes_a_few_dozen_legs_ending_where_the_odometry_ends() -> None:
    dt, v, radius = 0.05, 0.04, 0.3
    n = round(2 * 2 * math.pi * radius / v / dt)  # two laps at 50 ms samples: 1885
    poses = _ticks_for(np.full(n, v), np.full(n, -v / radius), dt)
    path = compress_odometry(poses)
    assert len(poses) > 1800
    # 4 pi of heading in steps of at most HEADING_STEP_RAD: 42, plus the rounding of counts
    assert 40 <= len(path.legs.length_m) <= 50
    _assert_ends_where_odometry_ends(poses, path)
    assert {step.kind for step in path.steps if isinstance(step, Turn)} == {"arc"}
    assert path_family(path) == ("arc", "cw")
    assert abs(path.net_turn_rad + 4 * math.pi) < 0.01
    # chords fall short of the arc by at most a^2/24 of it (module docstring)
    arc = n * v * dt
    assert arc * (1 - HEADING_STEP_RAD**2 / 24) - 0.002 < path.distance_m <= arc + 0.002


def test_every_leg_keeps_within_the_heading_step_and_the_leg_length() -> None:
    rng = np.random.default_rng(3)
    dt = 0.02
    v = np.repeat(rng.uniform(-0.3, 0.4, 40), 50)
    w = np.repeat(rng.uniform(-1.5, 1.5, 40), 50)
    poses = _ticks_for(v, w, dt, seed=4)
    path = compress_odometry(poses)
    _assert_ends_where_odometry_ends(poses, path)
    assert np.all(path.legs.length_m <= LEG_MAX_M + 1e-12)
    # a leg is a chord of a segment whose heading moved at most one step: its two
    # turns' arc part cannot exceed the step much (a count's rounding)
    assert len(path.legs.length_m) < len(poses) / 10


@pytest.mark.parametrize(
    ("v", "w", "family"),
    [
        (0.2, 0.0, ("straight", "forward")),
        (-0.2, 0.0, ("straight", "backward")),
        (0.0, 0.6, ("spin", "ccw")),
        (0.0, -0.6, ("spin", "cw")),
        (0.1, 0.4, ("arc", "ccw")),
    ],
)
def test_families_and_directions(v: float, w: float, family: tuple[str, str]) -> None:
    poses = _ticks_for(np.full(200, v), np.full(200, w), 0.05, seed=5)
    path = compress_odometry(poses)
    assert path_family(path) == family
    _assert_ends_where_odometry_ends(poses, path)


def test_a_spin_is_turns_of_kind_spin_and_its_drift_a_leg() -> None:
    n = 200
    # one wheel turns a little more: the centre drifts millimetres
    poses = _ticks_for(np.full(n, 0.0005), np.full(n, 0.8), 0.05, seed=6)
    path = compress_odometry(poses)
    turns = [step for step in path.steps if isinstance(step, Turn)]
    assert turns
    assert all(turn.kind == "spin" for turn in turns)
    assert path.distance_m < 0.01
    _assert_ends_where_odometry_ends(poses, path)


def test_a_spin_without_any_drift_carries_a_placeholder_leg() -> None:
    theta = np.linspace(0.0, math.pi, 50)
    poses = np.stack([np.zeros(50), np.zeros(50), theta], axis=1)
    path = compress_odometry(poses)
    assert path.steps == (Turn(math.pi, "spin"), Leg(1e-9))
    assert path_family(path) == ("spin", "ccw")


def test_wrapped_odometry_headings_are_unwrapped() -> None:
    poses = _ticks_for(np.full(300, 0.1), np.full(300, 1.0), 0.05, seed=7)
    wrapped = poses.copy()
    wrapped[:, 2] = np.angle(np.exp(1j * poses[:, 2]))
    a, b = compress_odometry(poses), compress_odometry(wrapped)
    assert abs(a.net_turn_rad - b.net_turn_rad) < 1e-9
    assert abs(a.net_turn_rad - 15.0) < 0.05


def test_looser_bounds_give_fewer_legs() -> None:
    dt, v, radius = 0.05, 0.04, 0.3
    n = 1885
    poses = _ticks_for(np.full(n, v), np.full(n, v / radius), dt)
    fine = compress_odometry(poses)
    coarse = compress_odometry(poses, CompressionBounds(heading_step_rad=0.6))
    assert len(coarse.legs.length_m) < 0.6 * len(fine.legs.length_m)
    _assert_ends_where_odometry_ends(poses, coarse)


@settings(max_examples=60, deadline=None)
@given(
    speeds=st.lists(
        st.tuples(
            st.floats(-0.5, 0.5),  # v, m/s
            st.floats(-2.0, 2.0),  # w, rad/s
            st.integers(1, 80),  # samples at that speed
        ),
        min_size=1,
        max_size=12,
    ),
    dt=st.sampled_from([0.01, 0.02, 0.05]),
)
def test_any_odometry_compresses_to_a_path_ending_where_it_ends(
    speeds: list[tuple[float, float, int]], dt: float
) -> None:
    v = np.concatenate([np.full(n, a) for a, _, n in speeds])
    w = np.concatenate([np.full(n, b) for _, b, n in speeds])
    theta = np.concatenate([[0.0], np.cumsum(w * dt)])
    chord = v * dt * np.sinc(w * dt / (2 * math.pi))
    mid = theta[:-1] + 0.5 * w * dt
    poses = np.stack(
        [
            np.concatenate([[0.0], np.cumsum(chord * np.cos(mid))]),
            np.concatenate([[0.0], np.cumsum(chord * np.sin(mid))]),
            theta,
        ],
        axis=1,
    )
    path = compress_odometry(poses)
    _assert_ends_where_odometry_ends(poses, path)
    assert np.all(path.legs.length_m <= LEG_MAX_M + 1e-12)
    assert len(path.legs.length_m) <= len(poses)
    family, direction = path_family(path)
    assert family in ("straight", "spin", "arc", "mixed")
    assert direction in ("forward", "backward", "cw", "ccw", "mixed")
