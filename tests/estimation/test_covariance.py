"""Pose covariance for any path: closed form against simulation, and the EKF model."""

from __future__ import annotations

import math

import numpy as np
import pytest

from odohil.errors import ParameterError
from odohil.science.covariance import (
    ekf_increment,
    ekf_moments,
    predicted_moments,
    simulated_moments,
)
from odohil.science.parameters import NOMAD150, ErrorParameters
from odohil.science.paths import Design, EncoderPath, Leg, polygonal_circle, square

# larger errors than the Nomad's, so that nonlinear effects are visible
ROUGH = ErrorParameters.from_paper_units(1.5, 0.05, 0.5, 2e-4)


@pytest.mark.parametrize(
    "path", [square(3.0), Design(1.5, 4.0, "reverse").path(), polygonal_circle(2.0, 6)]
)
def test_closed_form_matches_simulation(path: EncoderPath) -> None:
    exact = predicted_moments(path, ROUGH)
    sim = simulated_moments(path, ROUGH, 6000, seed=11, segment_m=0.002)
    assert np.all(np.abs(sim.mean - exact.mean) <= 4 * sim.mean_se)
    assert np.all(np.abs(sim.cov - exact.cov) <= 4 * sim.cov_se)


def test_simulated_standard_errors_shrink_with_trials() -> None:
    path = square(2.0)
    few = simulated_moments(path, NOMAD150, 400, seed=1, segment_m=0.01)
    many = simulated_moments(path, NOMAD150, 3600, seed=2, segment_m=0.01)
    np.testing.assert_allclose(few.cov_se[2, 2] / many.cov_se[2, 2], 3.0, rtol=0.2)


def test_ekf_step_matches_a_short_leg_exactly_to_leading_order() -> None:
    for length in (0.05, -0.05):
        exact = predicted_moments(EncoderPath((Leg(length),)), ROUGH)
        mean, q = ekf_increment(ROUGH, length, 0.0)
        np.testing.assert_allclose(mean, exact.mean, rtol=1e-3, atol=1e-12)
        # relative to the scale of each entry, sqrt(Var_i Var_j): the terms left
        # out are of relative order |E_R d| and K_theta |d|
        scale = np.sqrt(np.outer(np.diag(exact.cov), np.diag(exact.cov)))
        assert np.max(np.abs(q - exact.cov) / scale) < 0.01


def test_ekf_increment_rotates_with_the_heading() -> None:
    _, q0 = ekf_increment(NOMAD150, 0.1, 0.0)
    _, q90 = ekf_increment(NOMAD150, 0.1, math.pi / 2)
    assert q90[1, 1] == pytest.approx(q0[0, 0])
    assert q90[0, 0] == pytest.approx(q0[1, 1])


@pytest.mark.parametrize("design", [Design(1, 6.0), Design(20, 0.5), Design(0.5, 10.0)])
def test_ekf_propagation_converges_to_the_exact_covariance(design: Design) -> None:
    exact = predicted_moments(design.path(), NOMAD150).cov
    ekf = ekf_moments(design.path(), NOMAD150, step_m=0.01).cov
    scale = np.sqrt(np.outer(np.diag(exact), np.diag(exact)))
    # the linearisation misses terms of relative order K_theta * distance (< 1e-4 here)
    assert np.max(np.abs(ekf - exact) / scale) < 0.01


def test_bad_arguments() -> None:
    with pytest.raises(ParameterError):
        simulated_moments(square(1.0), NOMAD150, 1)
    with pytest.raises(ParameterError):
        ekf_moments(square(1.0), NOMAD150, step_m=0.0)
