"""What a validation pass rules out (odohil/science/validation.py, Detectable)
against Monte Carlo runs of the discrete model (odohil/science/simulator.py).

A calibration whose E_R (or E_T) is off by the stated detectable error is
caught by the named bias test in about ``power`` of validation sets, and by
the verdict at least as often; an error half as large is caught clearly less
often (so the number is not a loose bound that any shift would meet).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from odohil.errors import ParameterError
from odohil.science.parameters import ErrorParameters
from odohil.science.paths import EncoderPath, square
from odohil.science.simulator import simulate
from odohil.science.validation import (
    DETECTION_POWER,
    Detectable,
    detectable_errors,
    predict_path,
    validation_test,
)

N_SETS = 400
N_TRIALS = 15
MEASUREMENT_COV = np.diag([1e-6, 1e-6, 4e-6])
"""A tape-like measurement: 1 mm in x and y, 2 mrad in heading."""
ESTIMATE = ErrorParameters.from_paper_units(-0.5, -0.02, 0.1, 1e-4)
"""The calibration's estimate (E_R -0.5 deg/m, E_T -0.02, K_theta 0.1 deg^2/m, K_rho 1e-4 m)."""
ESTIMATE_SE = np.array([2e-3, 0.01, 1e-7, 1e-7])
"""Its standard errors (E_R rad/m, E_T, K_theta rad^2/m, K_rho m)."""
PATH = square(1.0, counter_clockwise=False)
FIELDS = ("e_r", "e_t")


def _detectable(path: EncoderPath, uncertain: bool) -> tuple[Detectable, ...]:
    """The estimate's detectable errors for N_TRIALS trials of ``path``."""
    prediction = predict_path(path, ESTIMATE)
    covs = np.broadcast_to(MEASUREMENT_COV, (N_TRIALS, 3, 3))
    poses = np.broadcast_to(prediction.mean, (N_TRIALS, 3))
    parameter_cov = np.diag(ESTIMATE_SE**2) if uncertain else None
    return validation_test(poses, [prediction] * N_TRIALS, covs, parameter_cov).detectable


def _rejections(
    index: int, shift: float, test: str, uncertain: bool, seed: int
) -> tuple[float, float]:
    """Fractions of N_SETS validation sets, simulated on a robot whose parameter
    ``index`` is ``shift`` (SI) from the calibration's, that ``test`` rejects
    and that the verdict rejects. With ``uncertain`` the calibration's
    estimate is also drawn with ESTIMATE_SE around its biased centre, its
    covariance given to the test."""
    rng = np.random.default_rng(seed)
    truth = replace(ESTIMATE, **{FIELDS[index]: getattr(ESTIMATE, FIELDS[index]) + shift})
    poses = simulate(PATH, truth, N_SETS * N_TRIALS, seed=rng, segment_m=0.002).pose_change
    poses += rng.multivariate_normal(np.zeros(3), MEASUREMENT_COV, size=poses.shape[0])
    sets = poses.reshape(N_SETS, N_TRIALS, 3)
    covs = np.broadcast_to(MEASUREMENT_COV, (N_TRIALS, 3, 3))
    parameter_cov = np.diag(ESTIMATE_SE**2) if uncertain else None
    fixed = predict_path(PATH, ESTIMATE)
    by_test, by_verdict = 0, 0
    for one in sets:
        prediction = fixed
        if uncertain:
            values = np.array(ESTIMATE.as_tuple()) + ESTIMATE_SE * rng.standard_normal(4)
            values[2:] = np.abs(values[2:])
            prediction = predict_path(PATH, ErrorParameters(*values))
        result = validation_test(one, [prediction] * N_TRIALS, covs, parameter_cov)
        by_test += next(t for t in result.bias if t.name == test).passed is False
        by_verdict += not result.passed
    return by_test / N_SETS, by_verdict / N_SETS


@pytest.mark.parametrize(
    ("index", "sign", "uncertain"),
    [(0, 1.0, False), (0, -1.0, True), (1, -1.0, False)],
    ids=["E_R+", "E_R-uncertain", "E_T-"],
)
def test_the_detectable_error_is_caught_at_the_stated_power(
    index: int, sign: float, uncertain: bool
) -> None:
    found = _detectable(PATH, uncertain)[index]
    assert found.power == DETECTION_POWER
    assert math.isfinite(found.shift)
    assert found.shift > 0
    se = math.sqrt(DETECTION_POWER * (1 - DETECTION_POWER) / N_SETS)
    test_rate, verdict_rate = _rejections(
        index, sign * found.shift, found.test, uncertain, seed=3 + index
    )
    assert abs(test_rate - DETECTION_POWER) < 4 * se, (found, test_rate)
    assert verdict_rate >= test_rate


def test_half_the_detectable_error_is_caught_clearly_less_often() -> None:
    found = _detectable(PATH, uncertain=False)[0]
    half_rate, _ = _rejections(0, 0.5 * found.shift, found.test, uncertain=False, seed=9)
    se = math.sqrt(DETECTION_POWER * (1 - DETECTION_POWER) / N_SETS)
    assert half_rate < DETECTION_POWER - 8 * se, (found, half_rate)


def test_more_trials_and_less_uncertainty_detect_smaller_errors() -> None:
    few = _detectable(PATH, uncertain=True)[0].shift
    exact = _detectable(PATH, uncertain=False)[0].shift
    assert exact < few
    mean = np.zeros((3, 1))
    mean[2, 0] = 4.0  # a square's heading moves 4 rad per rad/m of E_R
    w = np.diag([1e-6, 1e-6, 1e-4])
    one = detectable_errors(mean, w, 0.00125)[0]
    quarter = detectable_errors(mean, w / 4, 0.00125)[0]
    assert one.test == "bias theta"
    assert quarter.shift == pytest.approx(one.shift / 2)


def test_a_parameter_the_mean_does_not_follow_is_not_detectable() -> None:
    found = detectable_errors(np.zeros((3, 1)), np.eye(3), 0.00125)[0]
    assert found.shift == math.inf
    assert found.test == ""
    with pytest.raises(ParameterError, match="power must be in"):
        detectable_errors(np.zeros((3, 1)), np.eye(3), 0.00125, power=1.0)
