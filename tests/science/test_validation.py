"""The validation NEES and bias tests (odohil/science/validation.py) against
Monte Carlo runs of the discrete model (odohil/science/simulator.py).

Under the true model each of the eight tests (NEES and mean residual, each
overall, x, y, theta) rejects at its nominal rate, and the verdict (any test
at alpha/8) at most at alpha;
with the estimate's uncertainty drawn into the prediction the delta method
keeps the rates honest, and leaving it out does not; a robot whose E_R is
three times and K_theta nine times the model's is rejected.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from odohil.errors import ParameterError
from odohil.science.parameters import NOMAD150, ErrorParameters
from odohil.science.paths import Design, EncoderPath, square
from odohil.science.simulator import simulate
from odohil.science.validation import (
    ellipse_data,
    predict_path,
    validation_test,
)

N_SETS = 300
N_TRIALS = 8
LEVEL = 0.1
"""Rejection level at which each test's rate is checked (SE about 1.7 %)."""
MEASUREMENT_COV = np.diag([1e-6, 1e-6, 4e-6])
"""A tape-like measurement: 1 mm in x and y, 2 mrad in heading."""
ROBOT = ErrorParameters.from_paper_units(-0.5, -0.02, 0.1, 1e-4)
"""Larger than the Nomad's errors, so the path's spread is well above the tape's."""
ESTIMATE_SE = np.array([2e-3, 0.01, 1e-7, 1e-7])
"""Standard errors of a calibration (E_R rad/m, E_T, K_theta rad^2/m, K_rho m)."""


def _sets(
    path: EncoderPath, truth: ErrorParameters, seed: int, n_sets: int = N_SETS
) -> tuple[np.ndarray, np.random.Generator]:
    """n_sets validation sets of N_TRIALS simulated trials with measurement noise."""
    rng = np.random.default_rng(seed)
    poses = simulate(path, truth, n_sets * N_TRIALS, seed=rng, segment_m=0.002).pose_change
    noise = rng.multivariate_normal(np.zeros(3), MEASUREMENT_COV, size=poses.shape[0])
    return (poses + noise).reshape(n_sets, N_TRIALS, 3), rng


def _estimate(rng: np.random.Generator, truth: ErrorParameters) -> ErrorParameters:
    values = np.array(truth.as_tuple()) + ESTIMATE_SE * rng.standard_normal(4)
    values[2:] = np.abs(values[2:])
    return ErrorParameters(*values)


def _p_values(
    path: EncoderPath, truth: ErrorParameters, seed: int, *, uncertain: bool, with_cov: bool
) -> tuple[np.ndarray, np.ndarray]:
    """Per set: the four tests' p-values and the verdict at alpha = LEVEL."""
    sets, rng = _sets(path, truth, seed)
    covs = np.broadcast_to(MEASUREMENT_COV, (N_TRIALS, 3, 3))
    parameter_cov = np.diag(ESTIMATE_SE**2) if with_cov else None
    p_values, failed = [], []
    for poses in sets:
        fitted = _estimate(rng, truth) if uncertain else truth
        prediction = predict_path(path, fitted)
        result = validation_test(poses, [prediction] * N_TRIALS, covs, parameter_cov, alpha=LEVEL)
        p_values.append([t.p_value for t in result.tests])
        failed.append(not result.passed)
    return np.array(p_values), np.array(failed)


PATHS = {
    "forth-back k=2 l=2": Design(2, 2.0).path(),
    "reverse k=1 l=3": Design(1, 3.0, "reverse").path(),
    "square 2 m": square(2.0),
}


@pytest.mark.parametrize("name", sorted(PATHS))
def test_false_rejection_rate_is_nominal_with_the_estimate_uncertain(name: str) -> None:
    """The estimate drawn around the truth with ESTIMATE_SE, its covariance given."""
    p_values, failed = _p_values(PATHS[name], ROBOT, 11, uncertain=True, with_cov=True)
    se = math.sqrt(LEVEL * (1 - LEVEL) / N_SETS)
    rates = (p_values < LEVEL).mean(axis=0)
    assert np.all(np.abs(rates - LEVEL) < 4 * se), rates
    verdict_se = math.sqrt(LEVEL * (1 - LEVEL) / N_SETS)
    assert failed.mean() <= LEVEL + 3 * verdict_se, failed.mean()
    # p-values uniform: the mean p of the overall test near 1/2
    assert abs(p_values[:, 0].mean() - 0.5) < 4 * math.sqrt(1 / 12 / N_SETS)


def test_false_rejection_rate_is_nominal_at_the_nomad_values() -> None:
    p_values, _ = _p_values(
        PATHS["forth-back k=2 l=2"], NOMAD150, 5, uncertain=False, with_cov=False
    )
    se = math.sqrt(LEVEL * (1 - LEVEL) / N_SETS)
    rates = (p_values < LEVEL).mean(axis=0)
    assert np.all(np.abs(rates - LEVEL) < 4 * se), rates


def test_leaving_the_estimate_uncertainty_out_rejects_too_often() -> None:
    """The same sets without the delta-method term: the rate is far above nominal
    (so the term is needed, and the test above can fail)."""
    p_values, _ = _p_values(PATHS["square 2 m"], ROBOT, 11, uncertain=True, with_cov=False)
    se = math.sqrt(LEVEL * (1 - LEVEL) / N_SETS)
    assert (p_values[:, 0] < LEVEL).mean() > LEVEL + 6 * se


def test_a_robot_with_three_times_e_r_and_nine_times_k_theta_is_rejected() -> None:
    truth = NOMAD150
    robot = ErrorParameters(3 * truth.e_r, truth.e_t, 9 * truth.k_theta, truth.k_rho)
    path = PATHS["forth-back k=2 l=2"]
    sets, _ = _sets(path, robot, 7, n_sets=50)
    prediction = predict_path(path, truth)
    covs = np.broadcast_to(MEASUREMENT_COV, (N_TRIALS, 3, 3))
    rejected = [
        not validation_test(p, [prediction] * N_TRIALS, covs, np.diag(ESTIMATE_SE**2)).passed
        for p in sets
    ]
    assert all(rejected)


def test_a_shared_bias_the_nees_misses_is_rejected_by_the_bias_test() -> None:
    """Issue 20's hole: the prediction's spread 3 times the robot's (a K_theta
    inflated by a misfit elsewhere) and every trial's heading one predicted SD
    off. Each NEES test passes (about n (1 + 1/9) on n dof); the mean
    residual is 4 standard errors off and its test fails, naming theta."""
    path = PATHS["forth-back k=2 l=2"]
    prediction = predict_path(path, ROBOT)
    sd = np.sqrt(np.diag(prediction.cov + MEASUREMENT_COV))
    rng = np.random.default_rng(17)
    n = 16
    poses = prediction.mean + rng.normal(size=(n, 3)) * sd / 3.0
    poses[:, 2] += sd[2]
    result = validation_test(
        poses, [prediction] * n, np.broadcast_to(MEASUREMENT_COV, (n, 3, 3)), None
    )
    assert all(t.passed for t in (result.overall, *result.axes))
    assert not result.passed
    assert "bias theta" in result.failed()
    assert "heading mean residual +" in " ".join(result.reasons())
    assert result.to_json_dict()["bias"]["axes"]["theta"]["passed"] is False


def test_leaving_the_estimate_uncertainty_out_biases_the_bias_test() -> None:
    """The mean residual of the trials shares the estimate's error: without
    the delta-method term the bias test rejects clean sets far too often."""
    p_values, _ = _p_values(PATHS["square 2 m"], ROBOT, 11, uncertain=True, with_cov=False)
    se = math.sqrt(LEVEL * (1 - LEVEL) / N_SETS)
    assert (p_values[:, 4] < LEVEL).mean() > LEVEL + 6 * se


def test_jacobian_matches_the_closed_form_heading_drift() -> None:
    """d<Delta>/dE_R is the signed distance; d<Delta>/d(the rest) is 0."""
    design = Design(0.5, 3.0)
    prediction = predict_path(design.path(), NOMAD150)
    assert prediction.jacobian[2] == pytest.approx([3.0, 0.0, 0.0, 0.0], abs=1e-6)
    assert prediction.jacobian[:, 3] == pytest.approx([0.0, 0.0, 0.0], abs=1e-6)
    # x of a one-way run is (1 + E_T) l e^{-K l / 2}... to first order: dx/dE_T ~ l
    assert prediction.jacobian[0, 1] == pytest.approx(3.0, rel=1e-2)


def test_heading_residual_is_wrapped() -> None:
    path = square(1.0)
    prediction = predict_path(path, NOMAD150)
    pose = prediction.mean + np.array([0.0, 0.0, 2 * math.pi])
    result = validation_test(pose[None, :], [prediction], MEASUREMENT_COV[None])
    assert abs(result.residuals[0, 2]) < 1e-12
    assert result.passed


def test_bad_input_is_refused() -> None:
    prediction = predict_path(square(1.0), NOMAD150)
    with pytest.raises(ParameterError, match="alpha"):
        validation_test(np.zeros((1, 3)), [prediction], alpha=0.0)
    with pytest.raises(ParameterError, match="predictions"):
        validation_test(np.zeros((2, 3)), [prediction])
    with pytest.raises(ParameterError, match="4 x 4"):
        validation_test(np.zeros((1, 3)), [prediction], None, np.full((4, 4), np.inf))


def test_ellipse_holds_its_share_of_simulated_end_points() -> None:
    path = PATHS["forth-back k=2 l=2"]
    poses = simulate(path, ROBOT, 2000, seed=3, segment_m=0.002).pose_change
    data = ellipse_data(poses, predict_path(path, ROBOT), level=0.95)
    inverse = np.linalg.inv(data.cov)
    d = data.points - data.mean
    inside = np.einsum("ni,ij,nj->n", d, inverse, d) <= -2 * math.log(0.05)
    assert abs(inside.mean() - 0.95) < 4 * math.sqrt(0.95 * 0.05 / 2000)
    assert data.axes_m[0] >= data.axes_m[1] > 0
