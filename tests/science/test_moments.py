"""pose_moments: exact N -> infinity mean and covariance of (x, y, Delta).

Three independent checks: the deterministic and K_rho-only limits by hand,
the exact moments of the discrete model (segment sums, eqs. 26-28 and their
second-order analogues) extrapolated to zero segment length, and Monte Carlo
runs of the simulator with tolerances of 4 standard errors.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pytest

from odohil.science.moments import pose_moments
from odohil.science.parameters import NOMAD150, ErrorParameters
from odohil.science.paths import Design, EncoderPath, Leg, Turn, polygonal_circle, square
from odohil.science.simulator import segments_per_leg, simulate

EXAGGERATED = ErrorParameters.from_paper_units(20.0, -0.05, 200.0, 1e-3)
"""Every term matters: E_R 20 deg/m, 1+E_T 0.95, K_theta 200 deg^2/m, K_rho 1 mm."""

PAIRS = [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)]


@dataclass(frozen=True)
class Discrete:
    mean: np.ndarray
    cov: np.ndarray


def discrete_moments(path: EncoderPath, params: ErrorParameters, segment_m: float) -> Discrete:
    """Exact mean and covariance of the simulator's discrete model (not a limit).

    Segment i has signed encoder length sigma_i delta_i, ends at arc s_i, and
    translates along theta_i = thetatilde_i + W_i with Var W_i = K_theta s_i.
    Double sums over segment pairs are done with prefix sums.
    """
    legs = path.legs
    a_parts, s_parts, th_parts, d_parts = [], [], [], []
    for j in range(legs.length_m.size):
        n = segments_per_leg(float(legs.length_m[j]), segment_m)
        delta = legs.length_m[j] / n
        step = np.arange(1, n + 1) * delta
        theta = legs.heading_rad[j] + params.e_r * (legs.start_signed_m[j] + legs.sign[j] * step)
        a_parts.append((1 + params.e_t) * legs.sign[j] * delta * np.exp(1j * theta))
        s_parts.append(legs.start_arc_m[j] + step)
        th_parts.append(theta)
        d_parts.append(np.full(n, delta))
    a, s = np.concatenate(a_parts), np.concatenate(s_parts)
    theta, delta = np.concatenate(th_parts), np.concatenate(d_parts)
    k, kr = params.k_theta, params.k_rho

    mean_z = np.sum(a * np.exp(-k * s / 2))
    grow = a * np.exp(k * s / 2)
    before = np.cumsum(grow) - grow
    abs_sq = (
        np.sum(np.abs(a) ** 2)
        + 2 * np.sum(np.conj(a) * np.exp(-k * s / 2) * before).real
        + kr * delta.sum()
    )
    f = a * np.exp(-1.5 * k * s)
    before_f = np.cumsum(f) - f
    sq = (
        np.sum(a * a * np.exp(-2 * k * s))
        + 2 * np.sum(before_f * a * np.exp(-k * s / 2))
        + kr * np.sum(delta * np.exp(2j * theta - 2 * k * s))
    )
    cov_dz = np.sum(a * 1j * k * s * np.exp(-k * s / 2))
    c_abs = abs_sq - abs(mean_z) ** 2
    c_sq = sq - mean_z**2
    cov = np.array(
        [
            [(c_abs + c_sq.real) / 2, c_sq.imag / 2, cov_dz.real],
            [c_sq.imag / 2, (c_abs - c_sq.real) / 2, cov_dz.imag],
            [cov_dz.real, cov_dz.imag, k * path.distance_m],
        ]
    )
    mean_delta = path.net_turn_rad - path.winding_rad + params.e_r * path.signed_distance_m
    return Discrete(np.array([mean_z.real, mean_z.imag, mean_delta]), cov)


ODD_PATH = EncoderPath(
    (Leg(1.3), Turn(0.7), Leg(-0.4), Turn(-2.0), Leg(2.1), Leg(0.5), Turn(math.pi / 3), Leg(-1.0)),
    name="irregular",
)

PATHS = [
    Design(1, 2.0, "turn").path(),
    Design(1.5, 1.0, "reverse").path(),
    square(1.0),
    polygonal_circle(1.0, 7, counter_clockwise=False),
    ODD_PATH,
]


@pytest.mark.parametrize("path", PATHS, ids=lambda p: p.name)
def test_discrete_model_converges_to_pose_moments(path: EncoderPath) -> None:
    # the discrete moments are C + c delta + O(delta^2): Richardson-extrapolate
    coarse = discrete_moments(path, EXAGGERATED, 4e-3)
    fine = discrete_moments(path, EXAGGERATED, 2e-3)
    exact = pose_moments(path, EXAGGERATED)
    scale = path.distance_m
    assert np.allclose(2 * fine.mean - coarse.mean, exact.mean, rtol=0, atol=1e-6 * scale)
    assert np.allclose(2 * fine.cov - coarse.cov, exact.cov, rtol=0, atol=1e-6 * scale**2)
    # and the extrapolation is needed: plain segment sums are off by O(delta)
    assert not np.allclose(coarse.cov, exact.cov, rtol=0, atol=1e-6 * scale**2)


def test_deterministic_limit_is_the_scaled_encoder_path() -> None:
    params = ErrorParameters(e_r=0.0, e_t=0.1, k_theta=0.0, k_rho=0.0)
    moments = pose_moments(ODD_PATH, params)
    x, y, theta = ODD_PATH.encoder_end_pose()
    assert moments.mean == pytest.approx([1.1 * x, 1.1 * y, theta], abs=1e-13)
    assert np.abs(moments.cov).max() < 1e-14


def test_translation_noise_only() -> None:
    # K_theta = 0, no drift: headings are exact, so Var x = K_rho sum L cos^2 h
    side = 1.5
    moments = pose_moments(square(side), ErrorParameters(0.0, 0.0, 0.0, 2e-3))
    assert moments.cov == pytest.approx(np.diag([2e-3 * 2 * side, 2e-3 * 2 * side, 0.0]), abs=1e-15)
    assert moments.mean_square_distance == pytest.approx(2e-3 * 4 * side, rel=1e-13)


def test_heading_moments() -> None:
    moments = pose_moments(ODD_PATH, EXAGGERATED)
    signed = 1.3 - 0.4 + 2.1 + 0.5 - 1.0
    net_turn = 0.7 - 2.0 + math.pi / 3
    assert moments.mean[2] == pytest.approx(net_turn + EXAGGERATED.e_r * signed, rel=1e-13)
    assert moments.cov[2, 2] == pytest.approx(EXAGGERATED.k_theta * 5.3, rel=1e-13)


def test_covariance_is_symmetric_positive_definite() -> None:
    for path in PATHS:
        cov = pose_moments(path, EXAGGERATED).cov
        assert np.array_equal(cov, cov.T)
        assert np.linalg.eigvalsh(cov).min() > 0


# (path, params, trials, segment length): Monte Carlo against the exact moments
SIMULATED = [
    (Design(1, 6.0, "turn").path(), NOMAD150, 3000, 0.05),
    (Design(20, 0.5, "turn").path(), NOMAD150, 3000, 0.01),
    (Design(1, 6.0, "reverse").path(), NOMAD150, 3000, 0.002),
    (Design(0.5, 3.0, "turn").path(), EXAGGERATED, 3000, 0.002),
    (Design(1, 2.0, "turn").path(), EXAGGERATED, 3000, 0.002),
    (Design(1.5, 1.0, "reverse").path(), EXAGGERATED, 3000, 0.001),
    (Design(2, 1.0, "reverse").path(), EXAGGERATED, 3000, 0.001),
    (Design(20, 0.5, "turn").path(), EXAGGERATED, 3000, 0.005),
    (square(1.0), EXAGGERATED, 3000, 0.002),
    (polygonal_circle(1.0, 7), EXAGGERATED, 3000, 0.002),
    (ODD_PATH, EXAGGERATED, 3000, 0.002),
]


@pytest.mark.parametrize(
    ("path", "params", "n", "segment_m"),
    SIMULATED,
    ids=[f"{p.name} {'nomad' if q is NOMAD150 else 'big'}" for p, q, _, _ in SIMULATED],
)
def test_simulator_agrees_within_four_standard_errors(
    path: EncoderPath, params: ErrorParameters, n: int, segment_m: float
) -> None:
    exact = pose_moments(path, params)
    data = simulate(path, params, n, seed=20240611, segment_m=segment_m).pose_change
    mean = data.mean(axis=0)
    centred = data - mean
    se_mean = data.std(axis=0, ddof=1) / math.sqrt(n)
    # the simulator's bias (its exact discrete moments minus the limit) is at most
    # SE/5, so the 4 SE tolerance is not stretched by the discretisation
    discrete = discrete_moments(path, params, segment_m)
    assert np.all(np.abs(discrete.mean - exact.mean) < se_mean / 5)
    assert np.all(np.abs(mean - exact.mean) < 4 * se_mean)
    for i, j in PAIRS:
        product = centred[:, i] * centred[:, j]
        sample = product.sum() / (n - 1)
        se = product.std(ddof=1) / math.sqrt(n)
        assert abs(discrete.cov[i, j] - exact.cov[i, j]) < se / 5, (i, j)
        assert abs(sample - exact.cov[i, j]) < 4 * se, (i, j, sample, exact.cov[i, j], se)


def test_printed_decay_misses_the_simulator() -> None:
    # eqs. (29), (30) read literally: decay e^{-sigma_theta^2 s/2} with
    # sigma_theta^2 = K_theta rho, i.e. a decay rate rho times too large
    path = Design(1, 2.0, "turn").path()
    params = EXAGGERATED
    printed = ErrorParameters(
        params.e_r, params.e_t, params.k_theta * path.distance_m, params.k_rho
    )
    n = 3000
    data = simulate(path, params, n, seed=11, segment_m=0.01).pose_change
    se = data[:, :2].std(axis=0, ddof=1) / math.sqrt(n)
    misses = np.abs(data[:, :2].mean(axis=0) - pose_moments(path, printed).mean[:2]) / se
    hits = np.abs(data[:, :2].mean(axis=0) - pose_moments(path, params).mean[:2]) / se
    assert misses.max() > 10
    assert hits.max() < 4
