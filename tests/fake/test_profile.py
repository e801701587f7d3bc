"""Trapezoid planning: exact end, speed and acceleration limits, textbook duration."""

from __future__ import annotations

import math

from hypothesis import given, settings
from hypothesis import strategies as st

from fakes.nomad.profile import Profile, move_duration, plan_move, plan_velocity

positions = st.floats(-5000, 5000, allow_nan=False)
speeds = st.floats(1, 450)
accels = st.floats(1, 300)


def _samples(profile: Profile, n: int = 400) -> list[tuple[float, float, float]]:
    end = profile.end_time
    return [(t, *profile.at(t)[:2]) for t in (profile.t0 + end * i / n for i in range(n + 1))]


@settings(max_examples=200, deadline=None)
@given(p0=positions, target=positions, v0=st.floats(-600, 600), vmax=speeds, amax=accels)
def test_a_move_from_any_state_ends_at_rest_on_its_target(
    p0: float, target: float, v0: float, vmax: float, amax: float
) -> None:
    profile = Profile(0.0, p0, v0, plan_move(p0, v0, target, vmax, amax), target)
    p, v, done = profile.at(profile.end_time)
    assert (p, v, done) == (target, 0.0, True)
    # the integrated phases land on the target too (not only the snap at the end)
    p_int, v_int = profile._integrate(math.inf)
    assert abs(p_int - target) <= 1e-6 * max(1.0, abs(target), abs(p0), v0 * v0 / amax)
    assert abs(v_int) <= 1e-6 * max(1.0, abs(v0))
    for phase in profile.phases:
        assert abs(phase.accel) <= amax * (1 + 1e-12)
    if abs(v0) <= vmax:
        for _, _, v in _samples(profile):
            assert abs(v) <= vmax * (1 + 1e-9)


@given(d=st.floats(-5000, 5000), vmax=speeds, amax=accels)
def test_rest_to_rest_duration_is_the_textbook_one(d: float, vmax: float, amax: float) -> None:
    phases = plan_move(0.0, 0.0, d, vmax, amax)
    duration = sum(p.duration_s for p in phases)
    if vmax * vmax / amax >= abs(d):  # triangle: never reaches vmax
        expected = 2 * math.sqrt(abs(d) / amax)
    else:
        expected = abs(d) / vmax + vmax / amax
    assert math.isclose(duration, expected, rel_tol=1e-9, abs_tol=1e-12)
    assert math.isclose(move_duration(d, vmax, amax), expected, rel_tol=1e-9, abs_tol=1e-12)


def test_velocity_ramp_then_cruise() -> None:
    profile = Profile(0.0, 0.0, 0.0, plan_velocity(0.0, 150.0, 300.0))
    assert profile.at(0.25) == (300 * 0.25**2 / 2, 75.0, False)
    assert profile.at(10.5)[:2] == (150 * 0.5 / 2 + 150 * 10.0, 150.0)
    assert math.isinf(profile.end_time)
