"""The export formulas (odohil/science/exports.py) against the model and the simulator."""

from __future__ import annotations

import math

import numpy as np
import pytest
import yaml

from odohil.errors import ParameterError
from odohil.science.covariance import simulated_moments
from odohil.science.exports import (
    UNOBSERVED_VARIANCE,
    VARIANCE_FLOOR,
    Linearisation,
    amcl_alphas,
    diff_drive_covariance,
    odometry_covariance,
    process_noise,
    step_covariance,
)
from odohil.science.moments import pose_moments
from odohil.science.parameters import NOMAD150, ErrorParameters
from odohil.science.paths import EncoderPath, Leg
from odohil.session.results.exports import yaml_list, yaml_scalar

# Exaggerated so that the cross-track terms stand well above the Monte Carlo noise,
# with K_theta * a small so the leading-order step formula is exact to 0.2 %.
LOUD = ErrorParameters(e_r=0.05, e_t=-0.03, k_theta=2e-3, k_rho=1e-4)


def test_step_covariance_matches_the_simulator() -> None:
    """One straight step of 1 m, 6000 simulated runs: every entry of the step's
    covariance (along, cross, heading, in the chord's frame) within 4 SE."""
    step = 1.0
    sim = simulated_moments(EncoderPath((Leg(step),)), LOUD, 6000, seed=11, segment_m=0.005)
    # the simulator reports the start frame; the formula the chord's (E_R a / 2)
    c, s = math.cos(LOUD.e_r * step / 2), math.sin(LOUD.e_r * step / 2)
    rotate = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])
    cov = rotate @ sim.cov @ rotate.T
    se = np.abs(rotate) @ sim.cov_se @ np.abs(rotate).T
    expected = step_covariance(LOUD, step)
    for i in range(3):
        for j in range(3):
            assert abs(cov[i, j] - expected[i, j]) < 4 * se[i, j], (i, j, cov[i, j], expected)
    assert expected[1, 1] == pytest.approx((1 + LOUD.e_t) ** 2 * LOUD.k_theta / 3)
    assert expected[1, 2] == pytest.approx((1 + LOUD.e_t) * LOUD.k_theta / 2)


def test_odometry_msg_is_36_symmetric_positive_definite_with_the_formula() -> None:
    odo = odometry_covariance(NOMAD150, 0.01)
    m = np.array(odo.covariance).reshape(6, 6)
    assert len(odo.covariance) == 36
    np.testing.assert_array_equal(m, m.T)
    assert np.linalg.eigvalsh(m).min() > 0
    assert m[0, 0] == pytest.approx(NOMAD150.k_rho * 0.01)
    assert m[5, 5] == pytest.approx(NOMAD150.k_theta * 0.01)
    assert m[1, 1] == VARIANCE_FLOOR  # 1.2e-12 m^2 from the model
    assert odo.floored == ("y",)
    assert [m[i, i] for i in (2, 3, 4)] == [UNOBSERVED_VARIANCE] * 3
    # a long step needs no floor: the model's own cross-track variance
    long = np.array(odometry_covariance(NOMAD150, 1.0).covariance).reshape(6, 6)
    assert long[1, 1] == pytest.approx((1 + NOMAD150.e_t) ** 2 * NOMAD150.k_theta / 3)


def test_diff_drive_twist_is_one_step_over_the_period() -> None:
    lin = Linearisation(speed_m_per_s=0.4, rate_hz=20.0)
    dd = diff_drive_covariance(NOMAD150, lin)
    assert len(dd.pose_covariance_diagonal) == len(dd.twist_covariance_diagonal) == 6
    a, t = 0.02, 0.05
    assert dd.pose_covariance_diagonal[0] == pytest.approx(NOMAD150.k_rho * a)
    assert dd.twist_covariance_diagonal[0] == pytest.approx(NOMAD150.k_rho * a / t**2)
    assert dd.twist_covariance_diagonal[5] == pytest.approx(NOMAD150.k_theta * a / t**2)
    assert min(dd.pose_covariance_diagonal + dd.twist_covariance_diagonal) >= VARIANCE_FLOOR


def test_process_noise_is_per_second_at_the_speed() -> None:
    pn = process_noise(NOMAD150, 0.8)
    m = np.array(pn.matrix).reshape(15, 15)
    np.testing.assert_array_equal(m, np.diag(np.diag(m)))
    assert m[0, 0] == m[1, 1] == pytest.approx(NOMAD150.k_rho * 0.8)
    assert m[5, 5] == pytest.approx(NOMAD150.k_theta * 0.8)
    assert np.diag(m).min() > 0
    assert "vx" in pn.from_template
    assert "yaw" not in pn.from_template


def test_amcl_alphas_give_the_model_variances_at_the_update_distance() -> None:
    """Nav2's differential sampler on a straight update of d metres: translation
    variance alpha3 d^2, and two rotations of variance alpha2 d^2 each; these
    must be the model's exact along-track and heading variances."""
    lin = Linearisation(update_min_d_m=0.3)
    a = amcl_alphas(NOMAD150, lin)
    exact = pose_moments(EncoderPath((Leg(0.3),)), NOMAD150).cov
    assert 2 * a.alpha2 * 0.3**2 == pytest.approx(exact[2, 2], rel=1e-9)
    assert a.alpha3 * 0.3**2 == pytest.approx(exact[0, 0], rel=1e-3)
    assert a.alpha1 == a.alpha4 == VARIANCE_FLOOR
    assert a.floored == ("alpha1", "alpha4")


def test_zero_variance_rates_are_floored_never_zero() -> None:
    still = ErrorParameters(0.0, 0.0, 0.0, 0.0)
    lin = Linearisation()
    dd = diff_drive_covariance(still, lin)
    assert min(dd.pose_covariance_diagonal + dd.twist_covariance_diagonal) == VARIANCE_FLOOR
    assert set(dd.floored) == {"pose x", "pose y", "pose yaw", "twist vx", "twist vy", "twist wz"}
    assert min(np.diag(np.array(process_noise(still, 1.0).matrix).reshape(15, 15))) > 0
    a = amcl_alphas(still, lin)
    assert min(a.alpha1, a.alpha2, a.alpha3, a.alpha4, a.alpha5) == VARIANCE_FLOOR


@pytest.mark.parametrize("name", ["speed_m_per_s", "rate_hz", "update_min_d_m", "update_min_a_rad"])
@pytest.mark.parametrize("bad", [0.0, -1.0, math.inf, math.nan])
def test_a_bad_linearisation_is_refused(name: str, bad: float) -> None:
    with pytest.raises(ParameterError, match=name):
        Linearisation(**{name: bad})


@pytest.mark.parametrize(
    "value", [0.0, 1.0, -2.5, 1e-6, 3.6e-5, 1e-9, 1e6, 1e16, 1.5e300, -7e-300, 0.1 + 0.2]
)
def test_yaml_floats_read_back_as_the_same_float(value: float) -> None:
    text = yaml_scalar(value)
    parsed = yaml.safe_load(f"v: {text}")["v"]
    assert isinstance(parsed, float)
    assert parsed == value
    listed = yaml.safe_load(f"k: {yaml_list([value] * 13, 4)}")["k"]
    assert listed == [value] * 13


def test_yaml_refuses_non_finite_numbers() -> None:
    with pytest.raises(ParameterError, match="non-finite"):
        yaml_scalar(math.inf)


def test_the_worked_examples_of_docs_exports_md() -> None:
    """The Nomad 150 numbers docs/exports.md prints, at the default linearisation."""
    lin = Linearisation()
    dd = diff_drive_covariance(NOMAD150, lin)
    assert dd.pose_covariance_diagonal[0] == pytest.approx(3.6e-7)
    assert dd.pose_covariance_diagonal[5] == pytest.approx(3.655e-8, rel=1e-3)
    assert dd.twist_covariance_diagonal[0] == pytest.approx(9.0e-4)
    assert dd.twist_covariance_diagonal[1] == pytest.approx(2.93e-9, rel=2e-3)
    assert dd.twist_covariance_diagonal[5] == pytest.approx(9.14e-5, rel=1e-3)
    assert step_covariance(NOMAD150, 0.01)[1, 1] == pytest.approx(1.17e-12, rel=2e-3)
    one_metre = step_covariance(NOMAD150, 1.0)
    assert one_metre[1, 1] == pytest.approx(1.17e-6, rel=2e-3)
    assert one_metre[1, 2] == pytest.approx(1.79e-6, rel=2e-3)
    q = np.array(process_noise(NOMAD150, 0.5).matrix).reshape(15, 15)
    assert q[0, 0] == pytest.approx(1.8e-5)
    assert q[5, 5] == pytest.approx(1.828e-6, rel=1e-3)
    a = amcl_alphas(NOMAD150, lin)
    assert a.alpha2 == pytest.approx(7.31e-6, rel=1e-3)
    assert a.alpha3 == pytest.approx(1.44e-4)
    assert a.alpha5 == pytest.approx(4.68e-6, rel=1e-3)
