"""Fisher information: docs/paper-notes.md section 2's bound table, the score
identity, floor marks."""

from __future__ import annotations

import math

import numpy as np
import pytest

from odohil import units
from odohil.errors import ParameterError
from odohil.science.fisher import (
    cramer_rao,
    default_description,
    measurement_covariance,
    moment_derivatives,
    pose_spread_measurement,
    standard_errors,
    trial_information,
)
from odohil.science.floor_marks import marks_from_pose
from odohil.science.moments import pose_moments
from odohil.science.parameters import NOMAD150, ErrorParameters
from odohil.science.paths import Design

DESIGN_A = Design(1, 6.0, "turn")
DESIGN_B = Design(20, 0.5, "turn")
PAPER_PLAN = [(DESIGN_A, 30), (DESIGN_B, 30)]


def paper_units(se: np.ndarray) -> tuple[float, float, float, float]:
    """(E_R deg/m, K_theta deg^2/m, 1+E_T, K_rho m): the column order of
    docs/paper-notes.md section 2."""
    return (
        units.rad_per_m_to_deg_per_m(float(se[0])),
        units.rad2_per_m_to_deg2_per_m(float(se[2])),
        float(se[1]),
        float(se[3]),
    )


def test_bound_without_measurement_error_matches_notes() -> None:
    se = cramer_rao(PAPER_PLAN, NOMAD150)
    values = paper_units(se)
    assert values[0] == pytest.approx(0.00353, abs=0.000005)
    assert values[1] == pytest.approx(0.00162, abs=0.000005)
    assert values[2] == pytest.approx(0.0104, abs=0.00005)
    assert values[3] == pytest.approx(6.5e-6, abs=0.05e-6)


def test_bound_with_one_mm_floor_marks_matches_notes() -> None:
    # layout: screws A, B, C on a 0.2 m radius circle at 0, 120, 240 deg (A forward),
    # one cross distance from A's start mark to B's end mark; tape sigma 1 mm.
    description = default_description(0.001)
    model = pose_spread_measurement(description, NOMAD150, n_samples=4096, seed=1)
    values = paper_units(cramer_rao(PAPER_PLAN, NOMAD150, model))
    assert values[0] == pytest.approx(0.00406, abs=0.000005)
    assert values[1] == pytest.approx(0.00218, abs=0.000005)
    assert values[2] == pytest.approx(0.0162, abs=0.00005)
    assert values[3] == pytest.approx(6.6e-6, abs=0.05e-6)


def test_measurement_noise_only_loosens_the_bound() -> None:
    exact = cramer_rao(PAPER_PLAN, NOMAD150)
    noisy = cramer_rao(PAPER_PLAN, NOMAD150, np.diag([1e-6, 1e-6, 1e-5]))
    assert np.all(noisy > exact)


def test_score_covariance_matches_information() -> None:
    """Draw poses from the Gaussian model, differentiate the log-likelihood by
    plain central differences (independently of the information formula), and
    compare the empirical covariance of the score with the information."""
    params = NOMAD150
    design = DESIGN_A
    meas = np.diag([1e-6, 4e-7, 1.5e-5])
    moments = pose_moments(design.path(), params)
    rng = np.random.default_rng(20240601)
    n = 20000
    poses = rng.multivariate_normal(moments.mean, moments.cov + meas, size=n)

    def log_likelihood(values: np.ndarray) -> np.ndarray:
        m = pose_moments(design.path(), ErrorParameters(*values))
        s = m.cov + meas
        r = poses - m.mean
        quad = np.einsum("ni,ij,nj->n", r, np.linalg.inv(s), r)
        return -0.5 * (quad + np.linalg.slogdet(s)[1])

    base = np.array(params.as_tuple())
    scores = np.empty((n, 4))
    for a in range(4):
        h = 1e-4 * abs(base[a])
        up, down = base.copy(), base.copy()
        up[a] += h
        down[a] -= h
        scores[:, a] = (log_likelihood(up) - log_likelihood(down)) / (2 * h)

    info = trial_information(moment_derivatives(design.path(), params), meas)
    products = scores[:, :, None] * scores[:, None, :]
    empirical = products.mean(axis=0)
    standard_error = products.std(axis=0, ddof=1) / math.sqrt(n)
    assert np.all(np.abs(empirical - info) <= 4 * standard_error)
    mean_score_se = scores.std(axis=0, ddof=1) / math.sqrt(n)
    assert np.all(np.abs(scores.mean(axis=0)) <= 4 * mean_score_se)


def test_one_sided_derivatives_at_zero_variance_rate() -> None:
    # K_rho = 0 uses one-sided differences, 2.1e-8 m central ones (step 1e-9 m); with a large
    # measurement variance the information barely changes between the two
    meas = np.diag([1e-4, 1e-4, 1e-4])
    at_zero = ErrorParameters(NOMAD150.e_r, NOMAD150.e_t, NOMAD150.k_theta, 0.0)
    near = ErrorParameters(NOMAD150.e_r, NOMAD150.e_t, NOMAD150.k_theta, 2.1e-8)
    np.testing.assert_allclose(
        cramer_rao(PAPER_PLAN, at_zero, meas), cramer_rao(PAPER_PLAN, near, meas), rtol=0.01
    )


def test_singular_covariance_is_a_parameter_error() -> None:
    params = ErrorParameters(NOMAD150.e_r, NOMAD150.e_t, 0.0, NOMAD150.k_rho)
    with pytest.raises(ParameterError, match="singular"):
        cramer_rao(PAPER_PLAN, params)


def test_unidentified_parameter_is_named() -> None:
    information = np.diag([1e6, 0.0, 1e12, 1e10])
    with pytest.raises(ParameterError, match="E_T"):
        standard_errors(information)


def test_measurement_covariance_linearises_the_floor_mark_forward_model() -> None:
    description = default_description(0.001)
    pose = np.array([0.0027, 0.124, -0.042])
    h = 1e-7
    columns = []
    for i in range(3):
        up, down = pose.copy(), pose.copy()
        up[i] += h
        down[i] -= h
        columns.append(
            (
                marks_from_pose(description, up).as_array()
                - marks_from_pose(description, down).as_array()
            )
            / (2 * h)
        )
    jac = np.stack(columns, axis=1)
    expected = 1e-6 * np.linalg.inv(jac.T @ jac)
    np.testing.assert_allclose(measurement_covariance(description, pose), expected, rtol=1e-5)


def test_heading_error_of_design_a_is_about_a_quarter_degree() -> None:
    # docs/paper-notes.md section 3: about 0.23 deg from 1 mm distances on a 0.2 m circle
    description = default_description(0.001)
    mean = pose_moments(DESIGN_A.path(), NOMAD150).mean
    sd_deg = math.degrees(math.sqrt(measurement_covariance(description, mean)[2, 2]))
    assert sd_deg == pytest.approx(0.23, abs=0.01)
