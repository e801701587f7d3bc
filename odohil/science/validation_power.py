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

For any error, the spread parameters' (K_theta, K_rho) included,
:func:`verdict_power` gives the power of all eight tests against the robot's
true prediction (mean and covariance at the true parameters), n trials of
one path. Each test's statistic is then a quadratic form of Gaussian
residuals, a weighted sum of noncentral chi-squares
(:func:`~odohil.science.distributions.quadratic_form_sf`): the stacked
residuals of n trials have covariance I_n (x) S + 1 1^T (x) G (G = J Sigma J^T,
the estimate's shared error), which the basis (1 / sqrt(n), ...) splits into one
block S + n G carrying the mean sqrt(n) d and n - 1 blocks S; the predicted
and the true covariance share that basis, so the NEES is a sum over the
blocks. The verdict rejects when any test does: its power is at least the
best test's, the figure given. :func:`trials_to_catch` finds the fewest
trials whose best test reaches the wanted power.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from odohil.errors import ParameterError
from odohil.science import distributions
from odohil.science.paths import FloatArray
from odohil.science.validation import (
    AXES,
    DETECTION_POWER,
    N_TESTS,
    PathPrediction,
    bias_scale_dofs,
    nees_scale_dofs,
)
from odohil.units import wrap_angles

MAX_TRIALS = 10000
"""The CLI's largest --trials (odohil/science/limits.py, ``plan_n``)."""


@dataclass(frozen=True)
class TestPower:
    """The probability that n trials' tests catch an error.

    Attributes:
        trials: n.
        power: the best test's rejection probability.
        test: that test (``bias``, ``bias x``, ``bias y``, ``bias theta``;
            :func:`verdict_power` also ``overall``, ``x``, ``y``, ``theta``: the NEES).
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
) -> TestPower:
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
    return TestPower(n, power, test)


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


def _level(alpha: float, power: float) -> float:
    """Each test's level, alpha / 8, with ``power`` checked to lie above it."""
    level = alpha / N_TESTS
    if not (level < power < 1.0):
        raise ParameterError(f"power must be in ({level:g}, 1), got {power!r}")
    return level


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
    level = _level(alpha, power)
    if not (math.isfinite(shift) and shift > 0):
        raise ParameterError(f"the error to detect must be finite and > 0, got {shift!r}")

    def at(n: int) -> TestPower:
        return bias_power(
            prediction, n, index, shift,
            measurement_cov=measurement_cov, parameter_cov=parameter_cov, level=level,
        )  # fmt: skip

    return _fewest(at, power, max_trials, at(10**12).power)


def _fewest(
    at: Callable[[int], TestPower], power: float, max_trials: int, limit: float
) -> TrialPlan:
    """The fewest n in 1..max_trials with at(n).power >= power (power rises
    with n): doubling from 1, then halving the last gap."""
    at = functools.cache(at)
    low, high = 0, 1  # power(low) < power; high is the next count tried
    while at(high).power < power:
        if high >= max_trials:
            top = at(max_trials)
            return TrialPlan(None, top.power, top.test, limit)
        low, high = high, min(2 * high, max_trials)
    while high - low > 1:  # power(low) < power <= power(high)
        mid = (low + high) // 2
        if at(mid).power >= power:
            high = mid
        else:
            low = mid
    found = at(high)
    return TrialPlan(high, found.power, found.test, limit)


def _form(cov: FloatArray, true_cov: FloatArray, mean: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Q = z^T cov^-1 z for z ~ N(mean, true_cov) as sum_k w_k chi^2(1, nc_k):
    (w, nc). With cov = C C^T, y = C^-1 z ~ N(C^-1 mean, C^-1 true_cov C^-T)."""
    root = np.linalg.cholesky(cov)
    white = np.linalg.solve(root, np.linalg.solve(root, true_cov).T)
    values, vectors = np.linalg.eigh(0.5 * (white + white.T))
    values = np.clip(values, 0.0, None)
    shift = vectors.T @ np.linalg.solve(root, mean)
    safe = np.where(values > 0, values, 1.0)
    weights: FloatArray = values
    return weights, np.where(values > 0, shift**2 / safe, 0.0)


def verdict_power(
    prediction: PathPrediction,
    truth: PathPrediction,
    n: int,
    *,
    measurement_cov: FloatArray | None = None,
    parameter_cov: FloatArray | None = None,
    level: float,
    parameter_dofs: Sequence[float] | None = None,
) -> TestPower:
    """The power of the eight tests of n trials of one path, each at ``level``
    against the reference the test uses (the F law of a spread that is itself
    an estimate, :func:`~odohil.science.validation.nees_scale_dofs` and
    :func:`~odohil.science.validation.bias_scale_dofs`; ``parameter_dofs`` as
    :func:`~odohil.science.validation.validation_test` takes them), when the
    robot's trials follow ``truth`` (its mean and covariance at the true
    parameters) instead of ``prediction`` (module docstring): the best test."""
    if n < 1:
        raise ParameterError(f"trials must be at least 1, got {n}")
    r = np.zeros((3, 3)) if measurement_cov is None else np.asarray(measurement_cov)
    s, s_true = prediction.cov + r, truth.cov + r
    g = np.zeros((3, 3))
    if parameter_cov is not None:
        j = prediction.jacobian
        g = j @ np.asarray(parameter_cov, dtype=np.float64) @ j.T
    d = truth.mean - prediction.mean
    d[2] = float(wrap_angles(np.array([d[2]]))[0])
    d_cov = None if prediction.cov_jacobian is None else prediction.cov_jacobian[None]
    nees_dofs = nees_scale_dofs(d_cov, s[None], parameter_cov)
    bias_dofs = bias_scale_dofs(
        s / n + g, None if d_cov is None else d_cov[0] / n, prediction.jacobian,
        parameter_cov, parameter_dofs,
    )  # fmt: skip
    out: list[tuple[str, float]] = []
    for t, (name, axes) in enumerate(
        (("overall", [0, 1, 2]), *((a, [k]) for k, a in enumerate(AXES)))
    ):
        ix = np.ix_(axes, axes)
        w0, _ = _form(s[ix], s_true[ix], np.zeros(len(axes)))
        w1, nc1 = _form(s[ix] + n * g[ix], s_true[ix] + n * g[ix],
                        math.sqrt(n) * d[axes])  # fmt: skip
        k = len(axes)
        weights, dofs, ncs = w1, np.ones(k), nc1
        if n > 1:  # the n - 1 blocks without the shared error and the mean
            weights = np.concatenate([w0, w1])
            dofs = np.concatenate([np.full(k, n - 1.0), dofs])
            ncs = np.concatenate([np.zeros(k), nc1])
        threshold = distributions.chi2_estimated_scale_isf(level, k * n, nees_dofs[t])
        out.append((name, distributions.quadratic_form_sf(threshold, weights, dofs, ncs)))
        wb, ncb = _form(s[ix] / n + g[ix], s_true[ix] / n + g[ix], d[axes])
        bias = "bias" if name == "overall" else f"bias {name}"
        bias_threshold = distributions.chi2_estimated_scale_isf(level, k, bias_dofs[t])
        out.append((bias, distributions.quadratic_form_sf(bias_threshold, wb, 1.0, ncb)))
    test, power = max(out, key=lambda c: c[1])
    return TestPower(n, power, test)


def trials_to_catch(
    prediction: PathPrediction,
    truth: PathPrediction,
    *,
    measurement_cov: FloatArray | None = None,
    parameter_cov: FloatArray | None = None,
    alpha: float,
    power: float = DETECTION_POWER,
    max_trials: int = MAX_TRIALS,
    parameter_dofs: Sequence[float] | None = None,
) -> TrialPlan:
    """The fewest trials of one path whose best test (each at alpha / 8, as
    the verdict runs them) rejects with probability ``power`` a robot whose
    trials follow ``truth`` (:func:`verdict_power`); ``limit`` is the power
    at ``max_trials``.

    Raises:
        ParameterError: power outside (alpha / 8, 1).
    """
    level = _level(alpha, power)

    def at(n: int) -> TestPower:
        return verdict_power(
            prediction, truth, n,
            measurement_cov=measurement_cov, parameter_cov=parameter_cov, level=level,
            parameter_dofs=parameter_dofs,
        )  # fmt: skip

    return _fewest(at, power, max_trials, at(max_trials).power)
