"""The trials a validation needs to catch an error (odohil/science/validation_power.py),
against the detectable errors validate prints (odohil/science/validation.py).

Not yet checked against a Monte Carlo of the discrete model (issue 31 asks
for it); tests/science/test_validation_sensitivity.py checks the same
noncentral chi-square against it for the detectable errors.
"""

from __future__ import annotations

import numpy as np

from odohil.science.parameters import ErrorParameters
from odohil.science.paths import square
from odohil.science.validation import N_TESTS, predict_path, validation_test
from odohil.science.validation_power import trials_for_power

ALPHA = 0.01
ESTIMATE = ErrorParameters.from_paper_units(-0.5, -0.02, 0.1, 1e-4)
MEASUREMENT_COV = np.diag([1e-6, 1e-6, 4e-6])
PREDICTION = predict_path(square(1.0, counter_clockwise=False), ESTIMATE)


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
