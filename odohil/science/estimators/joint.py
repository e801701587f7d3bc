"""Joint maximum likelihood on every trial's (x, y, Delta).

The likelihood is the Gaussian one of :mod:`odohil.science.estimators.likelihood`
(model mean and covariance per design plus each trial's measurement
covariance), in phi = (E_R, E_T, log K_theta, log K_rho). It is maximised by
Fisher scoring with Levenberg damping (each step solves
(I + lambda diag I) step = -score, and is kept only if the likelihood rises);
from the paper-method start this converges in a few steps. If it does not,
``scipy.optimize.minimize`` (L-BFGS-B on the exact score) takes over from the
best point. Standard errors come from the expected information at the optimum.

Any model of :mod:`odohil.science.estimators.likelihood` (a
:class:`~odohil.science.estimators.likelihood.MomentModel` and its
:class:`~odohil.science.estimators.likelihood.Layout`) is fitted the same way;
the start point's model is the one fitted.
"""

from __future__ import annotations

import math
from collections.abc import Hashable, Sequence
from dataclasses import dataclass

import numpy as np

from odohil.science.estimators.likelihood import (
    DESIGN_MODEL,
    GroupStats,
    Layout,
    LikelihoodValue,
    ModelPoint,
    MomentModel,
    evaluate,
    from_phi,
    to_phi,
    with_moments,
)
from odohil.science.parameters import ErrorParameters
from odohil.science.paths import FloatArray

DECREMENT_TOLERANCE = 1e-8
"""Converged when score^T I^-1 score (the squared step in standard errors) is below this."""
_MAX_ITERATIONS = 60
_MAX_LOG_STEP = 2.0
"""Largest change of log K in one step (a factor e^2)."""
_FLOOR_JUMP = 10.0
"""A log K step below -this goes to the floor at once (see :func:`_limit`)."""
_LOG_K_FLOOR = math.log(1e-14)
_LOG_K_CEILING = math.log(1e2)
_FALLBACK_SCALE = 1e-3


@dataclass(frozen=True)
class JointFit:
    """The optimum of the likelihood.

    Attributes:
        params: the estimate of the four parameters, SI.
        covariance: (p, p) inverse expected information, SI (inf where
            singular), in the order of the layout (the four first).
        point: the model at the optimum, with derivatives (for warm starts).
        value: the likelihood there.
        iterations: scoring steps taken.
        converged: whether the Newton decrement fell below the tolerance.
    """

    params: ErrorParameters
    covariance: FloatArray
    point: ModelPoint
    value: LikelihoodValue
    iterations: int
    converged: bool

    @property
    def values(self) -> FloatArray:
        """(p,) every parameter of the layout, SI."""
        return self.point.layout.to_si(self.point.phi)


def designs_of(groups: Sequence[GroupStats]) -> list[Hashable]:
    """The distinct keys (designs) of the groups, in order."""
    return list(dict.fromkeys(g.key for g in groups if g.n > 0))


def start_phi(params: ErrorParameters, floor: ErrorParameters | None = None) -> FloatArray:
    """phi of a start point, with variance rates raised to at least ``floor``'s
    (or 1e-12) so that their logarithms exist."""
    k_theta = max(params.k_theta, floor.k_theta if floor else 0.0, 1e-12)
    k_rho = max(params.k_rho, floor.k_rho if floor else 0.0, 1e-12)
    return to_phi(ErrorParameters(params.e_r, params.e_t, k_theta, k_rho))


def _solve(info: FloatArray, rhs: FloatArray, damping: float) -> FloatArray:
    diag = info.diagonal().copy()
    diag[diag <= 0] = 1.0
    # info + damping * np.diag(diag), element by element the same floats (the
    # off-diagonal entries plus 0.0, the diagonal ones plus damping * diag)
    system = info + 0.0
    system.flat[:: diag.size + 1] = info.diagonal() + damping * diag
    scale = 1.0 / np.sqrt(diag)
    scaled = system * np.outer(scale, scale)
    step = np.linalg.lstsq(scaled, rhs * scale, rcond=1e-13)[0]
    result: FloatArray = step * scale
    return result


def _limit(phi: FloatArray, step: FloatArray, layout: Layout) -> FloatArray:
    """phi + step with every log K moving at most _MAX_LOG_STEP (the whole
    step scaled down), except that a variance rate the step would shrink by
    more than e^_FLOOR_JUMP goes straight to the floor (a rate the data put
    at 0 would otherwise take ten steps to get there; a wrong jump is
    rejected like any step that does not improve the fit)."""
    step = step.copy()
    rates = [i for i in layout.log_rates if step[i] >= -_FLOOR_JUMP]
    jumps = [i for i in layout.log_rates if step[i] < -_FLOOR_JUMP]
    largest = float(np.max(np.abs(step[rates]))) if rates else 0.0
    if largest > _MAX_LOG_STEP:
        step *= _MAX_LOG_STEP / largest
    step[jumps] = _LOG_K_FLOOR - phi[jumps]
    return layout.bounded(phi + step, _LOG_K_FLOOR, _LOG_K_CEILING)


def decrement(value: LikelihoodValue, held: Sequence[int] = ()) -> float:
    """score^T I^-1 score: the squared length of the remaining Newton step in
    standard-error units (over the parameters not ``held``)."""
    assert value.gradient is not None
    assert value.information is not None
    if not held:
        gradient = value.gradient
        step = _solve(value.information, gradient, 0.0)
        return float(abs(gradient @ step))
    free = [i for i in range(value.gradient.size) if i not in held]
    step = _solve(value.information[np.ix_(free, free)], value.gradient[free], 0.0)
    return float(abs(value.gradient[free] @ step))


def held_at_floor(phi: FloatArray, value: LikelihoodValue, layout: Layout) -> list[int]:
    """The variance rates at the floor of log K whose score still pushes them
    down: the optimum is on the boundary (K = 0 for all practical purposes),
    so they are held there and the others are fitted (and converge)."""
    if value.gradient is None:
        return []
    return [i for i in layout.log_rates if phi[i] <= _LOG_K_FLOOR + 1e-9 and value.gradient[i] > 0]


def _free_step(value: LikelihoodValue, held: Sequence[int], damping: float) -> FloatArray:
    assert value.gradient is not None
    assert value.information is not None
    if not held:
        return _solve(value.information, -value.gradient, damping)
    free = [i for i in range(value.gradient.size) if i not in held]
    step = np.zeros(value.gradient.size)
    step[free] = _solve(value.information[np.ix_(free, free)], -value.gradient[free], damping)
    return step


def covariance_si(point: ModelPoint, value: LikelihoodValue) -> FloatArray:
    """Inverse of the expected information, converted from phi to SI (inf rows
    for parameters the information does not determine)."""
    assert value.information is not None
    info = value.information
    size = info.shape[0]
    scale = np.sqrt(np.clip(np.diag(info), 0.0, None))
    if np.any(scale == 0):
        cov_phi = np.full((size, size), math.inf)
    else:
        scaled = info / np.outer(scale, scale)
        eigen = np.linalg.eigvalsh(scaled)
        if eigen[0] <= 1e-12 * eigen[-1]:
            cov_phi = np.full((size, size), math.inf)
        else:
            cov_phi = np.linalg.inv(scaled) / np.outer(scale, scale)
    jac = point.layout.jacobian(point.phi)
    with np.errstate(invalid="ignore"):
        cov: FloatArray = jac @ cov_phi @ jac.T
    cov[~np.isfinite(cov)] = math.inf
    return 0.5 * (cov + cov.T)


def _distance(value: LikelihoodValue, delta: FloatArray) -> float:
    """Length of a phi displacement in standard errors, sqrt(delta^T I delta)."""
    assert value.information is not None
    return math.sqrt(max(0.0, float(delta @ value.information @ delta)))


def refine(
    groups: Sequence[GroupStats],
    start: ModelPoint,
    max_iterations: int = _MAX_ITERATIONS,
    reuse_within: float = 0.0,
    cox_reid: bool = False,
) -> JointFit:
    """Fisher scoring from ``start`` (a point with derivatives for every design).

    ``reuse_within`` > 0: keep the derivatives of the model (the costly part)
    while the point stays within that many standard errors of where they were
    evaluated; the moments themselves are always exact. The optimum then
    solves the likelihood equations with derivatives that are off by a
    relative amount of that order, which moves it by a negligible fraction
    of a standard error.

    ``cox_reid``: solve the Cox-Reid adjusted score equation instead (see
    :mod:`odohil.science.estimators.likelihood`); a step is kept when it
    shrinks the Newton decrement.
    """
    point = start
    layout = start.layout
    value = evaluate(groups, point, cox_reid)
    if not math.isfinite(value.nll):
        raise FloatingPointError("the start point gives a singular covariance")
    damping = 0.0
    iterations = 0
    converged = False
    # the held rates and the decrement of ``value``, kept until it changes
    # (a rejected step leaves both as they are; an accepted Cox-Reid step has
    # just computed them at the new point)
    known: tuple[list[int], float] | None = None
    while iterations < max_iterations:
        assert value.gradient is not None
        assert value.information is not None
        if known is None:
            held = held_at_floor(point.phi, value, layout)
            current = decrement(value, held)
        else:
            held, current = known
        known = (held, current)
        if current < DECREMENT_TOLERANCE:
            converged = True
            break
        iterations += 1
        step = _free_step(value, held, damping)
        trial_phi = _limit(point.phi, step, layout)
        if cox_reid:
            # an estimating equation (score + adjustment = 0): steps are kept
            # when they shrink the Newton decrement
            if reuse_within > 0 and _distance(value, trial_phi - point.anchor) < reuse_within:
                moved = with_moments(point, point.moved(trial_phi, derivatives=False))
            else:
                moved = point.moved(trial_phi, derivatives=True)
            trial = evaluate(groups, moved, cox_reid=True)
            better = False
            if trial.gradient is not None:
                trial_held = held_at_floor(trial_phi, trial, layout)
                trial_decrement = decrement(trial, trial_held)
                better = trial_decrement < current
            if better:
                point, value = moved, trial
                known = (trial_held, trial_decrement)
                damping = 0.0 if damping <= 1e-3 else damping / 10.0
            else:
                damping = 1e-3 if damping == 0.0 else damping * 10.0
                if damping > 1e8:
                    break
            continue
        moved = point.moved(trial_phi, derivatives=False)
        trial = evaluate(groups, moved)
        if trial.nll <= value.nll + 1e-12 * abs(value.nll):
            if reuse_within > 0 and _distance(value, trial_phi - point.anchor) < reuse_within:
                point = with_moments(point, moved)
            else:
                point = point.moved(trial_phi, derivatives=True)
            value = evaluate(groups, point, cox_reid)
            known = None
            damping = 0.0 if damping <= 1e-3 else damping / 10.0
        else:
            damping = 1e-3 if damping == 0.0 else damping * 10.0
            if damping > 1e8:
                break
    return JointFit(
        from_phi(point.phi), covariance_si(point, value), point, value, iterations, converged
    )


def _scipy_fit(
    groups: Sequence[GroupStats], start: FloatArray, model: MomentModel = DESIGN_MODEL
) -> FloatArray:
    """L-BFGS-B on the NLL in scaled phi (the fallback)."""
    keys = designs_of(groups)
    layout = model.layout
    first = evaluate(groups, model.point(start, keys, derivatives=True))
    assert first.information is not None
    diag = np.diag(first.information)
    scale = np.where(diag > 0, 1.0 / np.sqrt(np.where(diag > 0, diag, 1.0)), _FALLBACK_SCALE)
    scale[list(layout.log_rates)] = np.where(diag > 0, scale, 1.0)[list(layout.log_rates)]

    def fun(u: FloatArray) -> tuple[float, FloatArray]:
        value = evaluate(groups, model.point(start + scale * u, keys, derivatives=True))
        if value.gradient is None:
            return 1e300, np.zeros(layout.size)
        return value.nll, value.gradient * scale

    bounds: list[tuple[float | None, float | None]] = [(None, None)] * layout.size
    for index, floor in layout.floors:
        bounds[index] = ((floor - start[index]) / scale[index], None)
    for i in layout.log_rates:
        bounds[i] = ((_LOG_K_FLOOR - start[i]) / scale[i], (_LOG_K_CEILING - start[i]) / scale[i])
    from scipy import optimize  # imported here: about 0.7 s of CPU, rarely needed

    result = optimize.minimize(
        fun,
        np.zeros(layout.size),
        jac=True,
        method="L-BFGS-B",
        bounds=bounds,
        options={"maxiter": 500},
    )
    best: FloatArray = start + scale * np.asarray(result.x, dtype=np.float64)
    return best


def joint_estimate(
    groups: Sequence[GroupStats],
    start: FloatArray,
    cox_reid: bool = False,
    model: MomentModel = DESIGN_MODEL,
) -> JointFit:
    """Maximum-likelihood estimate from phi ``start`` (see :func:`start_phi`);
    ``cox_reid``: of the adjusted likelihood; ``model``: whose likelihood
    (the four-parameter design model by default)."""
    keys = designs_of(groups)
    fit = refine(groups, model.point(start, keys, derivatives=True), cox_reid=cox_reid)
    if fit.converged:
        return fit
    rescue = _scipy_fit(groups, fit.point.phi, model)
    second = refine(groups, model.point(rescue, keys, derivatives=True), cox_reid=cox_reid)
    if second.converged:
        # a converged rescue wins, whatever the NLLs' last digits say: the
        # first refine may have crept to the same root without reaching the
        # tolerance (a rate near 0, tests/estimation/test_slow_convergence.py),
        # and the adjusted score's root is not the NLL's minimum anyway
        return second
    return second if second.value.nll <= fit.value.nll else fit
