"""How many validation trials catch a given calibration error (issue 31).

The bias tests of :func:`odohil.science.validation.validation_test` on n
trials of one path (each with prediction S = C + R per trial and mean
Jacobian J) see the mean residual's covariance

    W(n) = S / n + J Sigma J^T

(the estimate's error is shared by the trials, so its term does not shrink
with n). A true parameter Delta_j away from the estimate moves the mean
residual by J_j Delta_j, so the overall bias test's statistic is noncentral
chi-square(3) with noncentrality Delta_j^2 J_j^T W^-1 J_j and the axis-a
test's noncentral chi-square(1) with Delta_j^2 J_aj^2 / W_aa: the same
statistic and the same noncentrality as
:func:`~odohil.science.validation.detectable_errors`. The power of the
verdict (which rejects when any test does) is at least that of its best bias
test, the figure given here.

Since W(n) decreases with n, the power increases with n, towards the power
at W = J Sigma J^T: an error comparable with the calibration's own standard
error cannot be caught by any number of trials, and :func:`trials_for_power`
says so (``trials`` None).

Only the mean parameters (E_R, E_T, a fit's turn-scale errors) are covered:
the spread parameters (K_theta, K_rho) act through the NEES tests, whose power
this module does not compute yet.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from odohil.errors import ParameterError
from odohil.science import distributions
from odohil.science.paths import FloatArray
from odohil.science.validation import AXES, DETECTION_POWER, N_TESTS, PathPrediction

MAX_TRIALS = 10000
"""The CLI's largest --trials (odohil/science/limits.py, ``plan_n``)."""


@dataclass(frozen=True)
class BiasPower:
    """The probability that n trials' bias tests catch one parameter's error.

    Attributes:
        trials: n.
        power: the best bias test's rejection probability.
        test: that test (``bias``, ``bias x``, ``bias y``, ``bias theta``).
    """

    trials: int
    power: float
    test: str


def _bias_cov(
    prediction: PathPrediction,
    measurement_cov: FloatArray | None,
    parameter_cov: FloatArray | None,
    n: int,
) -> FloatArray:
    s = prediction.cov + (0.0 if measurement_cov is None else np.asarray(measurement_cov))
    w: FloatArray = s / n
    if parameter_cov is not None:
        j = prediction.jacobian
        w = w + j @ np.asarray(parameter_cov, dtype=np.float64) @ j.T
    return w


def bias_power(
    prediction: PathPrediction,
    n: int,
    index: int,
    shift: float,
    *,
    measurement_cov: FloatArray | None = None,
    parameter_cov: FloatArray | None = None,
    level: float,
) -> BiasPower:
    """The power of n trials of one path against parameter ``index`` (the
    prediction's Jacobian column) off by ``shift`` (SI), each test at ``level``."""
    if n < 1:
        raise ParameterError(f"trials must be at least 1, got {n}")
    w = _bias_cov(prediction, measurement_cov, parameter_cov, n)
    a = prediction.jacobian[:, index] * shift
    candidates = [
        ("bias", distributions.ncx2_sf(distributions.chi2_isf(level, 3), 3,
                                        float(a @ np.linalg.solve(w, a))))
    ]  # fmt: skip
    threshold = distributions.chi2_isf(level, 1)
    candidates += [
        (f"bias {name}", distributions.ncx2_sf(threshold, 1, float(a[k] ** 2 / w[k, k])))
        for k, name in enumerate(AXES)
    ]
    test, power = max(candidates, key=lambda c: c[1])
    return BiasPower(n, power, test)


@dataclass(frozen=True)
class TrialPlan:
    """The fewest trials that catch an error with the wanted power.

    Attributes:
        trials: that count, or None when even ``max_trials`` do not.
        power: the power at ``trials`` (or at ``max_trials`` when None).
        test: the bias test that catches it.
        limit: the power no number of trials exceeds (W = J Sigma J^T).
    """

    trials: int | None
    power: float
    test: str
    limit: float


def trials_for_power(
    prediction: PathPrediction,
    index: int,
    shift: float,
    *,
    measurement_cov: FloatArray | None = None,
    parameter_cov: FloatArray | None = None,
    alpha: float,
    power: float = DETECTION_POWER,
    max_trials: int = MAX_TRIALS,
) -> TrialPlan:
    """The fewest trials of one path whose bias tests (each at alpha / 8, as
    the verdict runs them) catch parameter ``index`` off by ``shift`` (SI)
    with probability ``power`` (module docstring).

    Raises:
        ParameterError: power outside (alpha / 8, 1), a shift not finite and > 0.
    """
    level = alpha / N_TESTS
    if not (level < power < 1.0):
        raise ParameterError(f"power must be in ({level:g}, 1), got {power!r}")
    if not (math.isfinite(shift) and shift > 0):
        raise ParameterError(f"the error to detect must be finite and > 0, got {shift!r}")

    def at(n: int) -> BiasPower:
        return bias_power(
            prediction, n, index, shift,
            measurement_cov=measurement_cov, parameter_cov=parameter_cov, level=level,
        )  # fmt: skip

    limit = at(10**12).power
    top = at(max_trials)
    if top.power < power:
        return TrialPlan(None, top.power, top.test, limit)
    low, high = 0, max_trials  # power(low) < power <= power(high); power rises with n
    while high - low > 1:
        mid = (low + high) // 2
        if at(mid).power >= power:
            high = mid
        else:
            low = mid
    found = at(high)
    return TrialPlan(high, found.power, found.test, limit)
