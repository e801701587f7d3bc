"""The trials a validation needs to catch an error (odohil/science/validation_power.py),
against the detectable errors validate prints (odohil/science/validation.py).

The power is checked against a Monte Carlo of the discrete model
(odohil/science/simulator.py): the planned count's, with the estimate's
uncertainty, and a count far below it, each within 4 Monte Carlo SE of the
rejection rate of N_SETS simulated validation sets; the power of all eight
tests (:func:`verdict_power`) likewise for a robot whose K_theta is off.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from odohil.science.parameters import ErrorParameters
from odohil.science.paths import square
from odohil.science.simulator import simulate
from odohil.science.validation import N_TESTS, PathPrediction, predict_path, validation_test
from odohil.science.validation_power import bias_power, trials_for_power, verdict_power

ALPHA = 0.01
ESTIMATE = ErrorParameters.from_paper_units(-0.5, -0.02, 0.1, 1e-4)
MEASUREMENT_COV = np.diag([1e-6, 1e-6, 4e-6])
PATH = square(1.0, counter_clockwise=False)
PREDICTION = predict_path(PATH, ESTIMATE)
N_SETS = 300


def _detectable_e_r(n: int, parameter_cov: np.ndarray) -> float:
    covs = np.broadcast_to(MEASUREMENT_COV, (n, 3, 3))
    poses = np.broadcast_to(PREDICTION.mean, (n, 3))
    result = validation_test(poses, [PREDICTION] * n, covs, parameter_cov, alpha=ALPHA)
    return result.detectable[0].shift


def test_the_planned_count_is_the_fewest_whose_detectable_error_is_small_enough() -> None:
    parameter_cov = np.diag([2e-3, 0.01, 1e-7, 1e-7]) ** 2
    shift = np.radians(0.55)  # E_R off by 0.55 deg/m: 15 trials
    plan = trials_for_power(
        PREDICTION, 0, shift, measurement_cov=MEASUREMENT_COV, parameter_cov=parameter_cov,
        alpha=ALPHA,
    )  # fmt: skip
    assert plan.trials is not None
    assert plan.trials > 1
    assert plan.power >= 0.9
    assert _detectable_e_r(plan.trials, parameter_cov) <= shift
    assert _detectable_e_r(plan.trials - 1, parameter_cov) > shift


def test_an_error_within_the_calibrations_own_uncertainty_cannot_be_planned() -> None:
    se = np.radians(0.5)  # the calibration's E_R is uncertain by 0.5 deg/m
    parameter_cov = np.diag([se, 0.01, 1e-7, 1e-7]) ** 2
    plan = trials_for_power(
        PREDICTION, 0, se, measurement_cov=MEASUREMENT_COV, parameter_cov=parameter_cov,
        alpha=ALPHA,
    )  # fmt: skip
    assert plan.trials is None
    assert plan.power < 0.9
    assert plan.limit < 0.9
    assert plan.limit > ALPHA / N_TESTS


def _caught(n: int, shift: float, test: str, parameter_cov: np.ndarray | None, seed: int) -> float:
    """The fraction of N_SETS validation sets of n trials, simulated by the
    discrete model on a robot whose E_R is ``shift`` (rad/m) above the
    estimate, that the bias test ``test`` rejects. With ``parameter_cov`` the
    calibration's estimate is drawn around its centre too, and that covariance
    given to the test."""
    rng = np.random.default_rng(seed)
    truth = replace(ESTIMATE, e_r=ESTIMATE.e_r + shift)
    poses = simulate(PATH, truth, N_SETS * n, seed=rng, segment_m=0.004).pose_change
    poses += rng.multivariate_normal(np.zeros(3), MEASUREMENT_COV, size=poses.shape[0])
    covs = np.broadcast_to(MEASUREMENT_COV, (n, 3, 3))
    se = None if parameter_cov is None else np.sqrt(np.diag(parameter_cov))
    caught = 0
    for one in poses.reshape(N_SETS, n, 3):
        prediction = PREDICTION
        if se is not None:
            values = np.array(ESTIMATE.as_tuple()) + se * rng.standard_normal(4)
            values[2:] = np.abs(values[2:])
            prediction = predict_path(PATH, ErrorParameters(*values))
        result = validation_test(one, [prediction] * n, covs, parameter_cov, alpha=ALPHA)
        caught += not next(t for t in result.bias if t.name == test).passed
    return caught / N_SETS


@pytest.mark.parametrize(
    ("planned", "uncertain"), [(True, True), (False, False)], ids=["planned", "three-trials"]
)
def test_the_power_is_the_discrete_models_rejection_rate(planned: bool, uncertain: bool) -> None:
    parameter_cov = np.diag([2e-3, 0.01, 1e-7, 1e-7]) ** 2 if uncertain else None
    shift = np.radians(0.55 if planned else 0.3)
    if planned:  # the count planned for power 0.9 (15 trials), the estimate uncertain
        plan = trials_for_power(
            PREDICTION, 0, shift, measurement_cov=MEASUREMENT_COV, parameter_cov=parameter_cov,
            alpha=ALPHA,
        )  # fmt: skip
        assert plan.trials is not None
        n = plan.trials
    else:  # 3 trials of E_R off by 0.3 deg/m, the estimate exact: power about 0.5
        n = 3
    expected = bias_power(
        PREDICTION, n, 0, shift, measurement_cov=MEASUREMENT_COV, parameter_cov=parameter_cov,
        level=ALPHA / N_TESTS,
    )  # fmt: skip
    rate = _caught(n, shift, expected.test, parameter_cov, seed=11 + n)
    mc_se = math.sqrt(expected.power * (1 - expected.power) / N_SETS)
    assert abs(rate - expected.power) < 4 * mc_se, (n, expected, rate)


def test_the_spread_power_is_the_discrete_models_rejection_rate() -> None:
    # a robot whose K_theta is three times the estimate's, 12 trials: the
    # heading NEES catches it with probability about 0.5
    parameter_cov = np.diag([2e-3, 0.01, 1e-7, 1e-7]) ** 2
    truth = replace(ESTIMATE, k_theta=3 * ESTIMATE.k_theta)
    n = 12
    expected = verdict_power(
        PREDICTION, predict_path(PATH, truth), n, measurement_cov=MEASUREMENT_COV,
        parameter_cov=parameter_cov, level=ALPHA / N_TESTS,
    )  # fmt: skip
    assert expected.test == "theta"
    rng = np.random.default_rng(5)
    poses = simulate(PATH, truth, N_SETS * n, seed=rng, segment_m=0.004).pose_change
    poses += rng.multivariate_normal(np.zeros(3), MEASUREMENT_COV, size=poses.shape[0])
    covs = np.broadcast_to(MEASUREMENT_COV, (n, 3, 3))
    caught = 0
    for one in poses.reshape(N_SETS, n, 3):
        result = validation_test(one, [PREDICTION] * n, covs, parameter_cov, alpha=ALPHA)
        caught += not next(t for t in result.axes if t.name == "theta").passed
    mc_se = math.sqrt(expected.power * (1 - expected.power) / N_SETS)
    assert abs(caught / N_SETS - expected.power) < 4 * mc_se, (expected, caught / N_SETS)


def test_the_verdicts_power_is_the_bias_power_when_only_the_mean_moves() -> None:
    # the spread known (no cov_jacobian): both against the chi-square itself
    parameter_cov = np.diag([2e-3, 0.01, 1e-7, 1e-7]) ** 2
    shift = np.radians(0.3)
    known = replace(PREDICTION, cov_jacobian=None)
    truth = PathPrediction(PREDICTION.mean + PREDICTION.jacobian[:, 0] * shift,
                           PREDICTION.cov, PREDICTION.jacobian)  # fmt: skip
    for n in (1, 4):
        bias = bias_power(
            PREDICTION, n, 0, shift, measurement_cov=MEASUREMENT_COV,
            parameter_cov=parameter_cov, level=ALPHA / N_TESTS,
        )  # fmt: skip
        verdict = verdict_power(
            known, truth, n, measurement_cov=MEASUREMENT_COV,
            parameter_cov=parameter_cov, level=ALPHA / N_TESTS,
        )  # fmt: skip
        assert verdict.power == pytest.approx(bias.power, abs=1e-6)
        assert verdict.power >= bias.power - 1e-6


def test_the_spreads_own_uncertainty_keeps_the_nees_tests_at_their_level() -> None:
    """The delta method of the spread (PathPrediction.cov_jacobian): a
    calibration whose K_theta and K_rho are uncertain by 30 %, validated on 30
    trials, each set with its own estimate drawn around the truth. The per-axis
    NEES tests reject at their level (within 4 SE); without the spread's
    uncertainty the heading test rejects far more often (issue 31)."""
    truth = ESTIMATE
    se = np.array([2e-3, 0.01, 0.3 * truth.k_theta, 0.3 * truth.k_rho])
    n, sets, alpha = 30, 200, 0.5
    level = alpha / N_TESTS
    rng = np.random.default_rng(1)
    poses = simulate(PATH, truth, sets * n, seed=rng, segment_m=0.004).pose_change
    poses += rng.multivariate_normal(np.zeros(3), MEASUREMENT_COV, size=poses.shape[0])
    covs = np.broadcast_to(MEASUREMENT_COV, (n, 3, 3))
    with_it, without = np.zeros(3), 0
    for one in poses.reshape(sets, n, 3):
        values = np.array(truth.as_tuple()) + se * rng.standard_normal(4)
        values[2:] = np.abs(values[2:])
        prediction = predict_path(PATH, ErrorParameters(*values))
        tested = validation_test(one, [prediction] * n, covs, np.diag(se**2), alpha=alpha)
        with_it += [not t.passed for t in tested.axes]
        plain = replace(prediction, cov_jacobian=None)
        blind = validation_test(one, [plain] * n, covs, np.diag(se**2), alpha=alpha)
        without += not blind.axes[2].passed
    mc_se = math.sqrt(level * (1 - level) / sets)
    assert np.all(np.abs(with_it / sets - level) < 4 * mc_se), with_it / sets
    assert without / sets > level + 4 * mc_se, without / sets
