"""pose_moments with turn errors (e_turn per turn class, K_spin): against the
exact moments of the discrete model and a Monte Carlo simulation of it
(odohil/science/diff_drive.py simulate_turn_errors), within 4 SE."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pytest

from odohil.science.diff_drive import simulate_turn_errors
from odohil.science.moments import TurnErrors, pose_moments
from odohil.science.parameters import ErrorParameters
from odohil.science.paths import EncoderPath, Leg, Turn, turn_class_index
from odohil.science.simulator import segments_per_leg

BIG = ErrorParameters.from_paper_units(5.0, -0.03, 50.0, 5e-4)
TURNS = TurnErrors(spin_ccw=-0.05, spin_cw=0.03, arc_ccw=-0.08, arc_cw=0.04, k_spin=0.02)
PAIRS = [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)]


def arc_circle(radius_m: float, laps: float, n_legs: int, ccw: bool) -> EncoderPath:
    """A circle cut into short legs, its heading changes as arc turns."""
    angle = 2 * math.pi * laps / n_legs * (1 if ccw else -1)
    chord = 2 * radius_m * math.sin(abs(angle) / 2)
    steps: list[Leg | Turn] = [Turn(angle / 2, "arc")]
    for i in range(n_legs):
        steps.append(Leg(chord))
        steps.append(Turn(angle if i < n_legs - 1 else angle / 2, "arc"))
    return EncoderPath(tuple(steps), name=f"arc circle {laps} laps {'ccw' if ccw else 'cw'}")


MIXED = EncoderPath(
    (
        Turn(0.4),
        Leg(1.2),
        Turn(-1.3),
        Leg(0.6),
        Turn(0.9, "arc"),
        Leg(-0.5),
        Turn(-0.6, "arc"),
        Leg(1.0),
        Turn(2.0),
        Leg(0.4),
        Turn(-0.7),
    ),
    name="mixed spins and arcs",
)
SQUARE_SPINS = EncoderPath(
    tuple(s for _ in range(4) for s in (Leg(0.75), Turn(-math.pi / 2))), name="cw square"
)
PATHS = [MIXED, SQUARE_SPINS, arc_circle(0.3, 2, 24, ccw=True), arc_circle(0.5, 1, 16, ccw=False)]


@dataclass(frozen=True)
class Discrete:
    mean: np.ndarray
    cov: np.ndarray


def discrete_moments(
    path: EncoderPath, params: ErrorParameters, turns: TurnErrors, segment_m: float
) -> Discrete:
    """Exact mean and covariance of the discrete model with turn errors, by
    segment sums (written from the model, not from odohil/science/moments.py):
    segment i translates along theta_i + X_i, Var X_i = V_i = K_theta s_i +
    K_spin (|angle| spun before it)."""
    scales = turns.scales
    heading, signed, arc, spun, turned = 0.0, 0.0, 0.0, 0.0, 0.0
    a_parts, v_parts, th_parts, d_parts = [], [], [], []
    for step in path.steps:
        if isinstance(step, Turn):
            if step.angle_rad != 0.0:
                heading += step.angle_rad
                turned += scales[turn_class_index(step)] * step.angle_rad
                if step.kind == "spin":
                    spun += abs(step.angle_rad)
            continue
        length = abs(step.length_m)
        sign = math.copysign(1.0, step.length_m)
        n = segments_per_leg(length, segment_m)
        delta = length / n
        ends = np.arange(1, n + 1) * delta
        theta = heading + turned + params.e_r * (signed + sign * ends)
        a_parts.append((1 + params.e_t) * sign * delta * np.exp(1j * theta))
        v_parts.append(params.k_theta * (arc + ends) + turns.k_spin * spun)
        th_parts.append(theta)
        d_parts.append(np.full(n, delta))
        arc += length
        signed += step.length_m
    a, v = np.concatenate(a_parts), np.concatenate(v_parts)
    theta, delta = np.concatenate(th_parts), np.concatenate(d_parts)
    kr = params.k_rho
    mean_z = np.sum(a * np.exp(-v / 2))
    grow = a * np.exp(v / 2)
    before = np.cumsum(grow) - grow
    abs_sq = (
        np.sum(np.abs(a) ** 2)
        + 2 * np.sum(np.conj(a) * np.exp(-v / 2) * before).real
        + kr * delta.sum()
    )
    f = a * np.exp(-1.5 * v)
    before_f = np.cumsum(f) - f
    sq = (
        np.sum(a * a * np.exp(-2 * v))
        + 2 * np.sum(before_f * a * np.exp(-v / 2))
        + kr * np.sum(delta * np.exp(2j * theta - 2 * v))
    )
    cov_dz = np.sum(a * 1j * v * np.exp(-v / 2))
    c_abs = abs_sq - abs(mean_z) ** 2
    c_sq = sq - mean_z**2
    var_delta = params.k_theta * arc + turns.k_spin * spun
    cov = np.array(
        [
            [(c_abs + c_sq.real) / 2, c_sq.imag / 2, cov_dz.real],
            [c_sq.imag / 2, (c_abs - c_sq.real) / 2, cov_dz.imag],
            [cov_dz.real, cov_dz.imag, var_delta],
        ]
    )
    mean_delta = heading - path.winding_rad + params.e_r * signed + turned
    return Discrete(np.array([mean_z.real, mean_z.imag, mean_delta]), cov)


@pytest.mark.parametrize("path", PATHS, ids=lambda p: p.name)
def test_discrete_model_converges_to_pose_moments(path: EncoderPath) -> None:
    coarse = discrete_moments(path, BIG, TURNS, 4e-3)
    fine = discrete_moments(path, BIG, TURNS, 2e-3)
    exact = pose_moments(path, BIG, TURNS)
    scale = path.distance_m
    assert np.allclose(2 * fine.mean - coarse.mean, exact.mean, rtol=0, atol=1e-6 * scale)
    assert np.allclose(2 * fine.cov - coarse.cov, exact.cov, rtol=0, atol=1e-6 * scale**2)


@pytest.mark.parametrize("path", PATHS, ids=lambda p: p.name)
def test_simulator_agrees_within_four_standard_errors(path: EncoderPath) -> None:
    n, segment_m = 4000, 0.002
    exact = pose_moments(path, BIG, TURNS)
    data = simulate_turn_errors(path, BIG, TURNS, n, seed=20261125, segment_m=segment_m)
    poses = data.pose_change
    mean = poses.mean(axis=0)
    centred = poses - mean
    se_mean = poses.std(axis=0, ddof=1) / math.sqrt(n)
    discrete = discrete_moments(path, BIG, TURNS, segment_m)
    assert np.all(np.abs(discrete.mean - exact.mean) < se_mean / 5)
    assert np.all(np.abs(mean - exact.mean) < 4 * se_mean), (mean, exact.mean, se_mean)
    for i, j in PAIRS:
        product = centred[:, i] * centred[:, j]
        sample = product.sum() / (n - 1)
        se = product.std(ddof=1) / math.sqrt(n)
        assert abs(discrete.cov[i, j] - exact.cov[i, j]) < se / 5, (i, j)
        assert abs(sample - exact.cov[i, j]) < 4 * se, (i, j, sample, exact.cov[i, j], se)


def test_exact_turns_model_misses_the_simulator() -> None:
    # the turn errors matter: the exact-turn moments are far from the simulation
    path = PATHS[0]
    n = 4000
    poses = simulate_turn_errors(path, BIG, TURNS, n, seed=7, segment_m=0.002).pose_change
    se = poses.std(axis=0, ddof=1) / math.sqrt(n)
    assert np.max(np.abs(poses.mean(axis=0) - pose_moments(path, BIG).mean) / se) > 10


def test_zero_turn_errors_are_the_paper_model() -> None:
    for path in PATHS:
        plain = pose_moments(path, BIG)
        zero = pose_moments(path, BIG, TurnErrors())
        assert np.array_equal(plain.mean, zero.mean)
        assert np.array_equal(plain.cov, zero.cov)


def test_turn_scale_and_spin_variance_by_hand() -> None:
    # heading: E[Delta] gains sum e_c a, Var Delta gains K_spin sum |a| over spins
    moments = pose_moments(MIXED, BIG, TURNS)
    plain = pose_moments(MIXED, BIG)
    gained = -0.05 * (0.4 + 2.0) + 0.03 * (-1.3 - 0.7) - 0.08 * 0.9 + 0.04 * (-0.6)
    assert moments.mean[2] - plain.mean[2] == pytest.approx(gained, rel=1e-12)
    assert moments.cov[2, 2] - plain.cov[2, 2] == pytest.approx(0.02 * 4.4, rel=1e-12)
