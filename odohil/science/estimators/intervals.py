"""Confidence intervals that stay honest at small n.

Two levels are given for every parameter: 95 % (``ci95``) and the
4-sigma-equivalent 1 - 2 Phi(-4) = 99.9937 % (``ci_4sigma``), the range outside
which the truth counts as "confidently wrong" (bench/operator_faults.py).

- **K_theta and K_rho: profile likelihood.** The variance rates are
  estimated like variances: their sampling distribution is skewed (chi^2-like),
  so an estimate that came out low also has a small Wald standard error, and a
  symmetric interval around it misses the truth above. The interval is the set
  of psi = log K whose profile deviance
  D(psi) = 2 [NLL_CR(psi, lambda_psi) - NLL_CR(psi_hat, lambda_hat)]
  stays below the chi^2(1) quantile of the level (1.96^2 at 95 %, 16 at the
  4-sigma level), where NLL_CR is the Cox-Reid adjusted likelihood
  (odohil/science/estimators/likelihood.py) and lambda_psi the other three
  parameters re-fitted with psi held. The end points are found by a
  safeguarded secant search on the signed root
  r(psi) = sign(psi - psi_hat) sqrt(D), nearly linear in psi, from the Wald
  guess; above an estimate on the floor of log K (or with a very wide Wald
  interval) the search runs in sqrt(K), where r is nearly linear instead,
  from where the score and curvature in K at the estimate put the level.
  The nuisance re-fit is Newton's method with the model's derivatives taken
  at the estimate (the moments, hence the likelihood, are exact at every
  point), warm-started along the profile's tangent, a nuisance rate on the
  floor held there, run until its Newton decrement is below 1e-3 (see
  :class:`_Profile`). A bound the deviance never reaches within the
  estimator's range of log K is open: 0 below, inf above.
  When the trials spread more than the Gaussian likelihood says (heavy-tailed
  tape errors), the threshold is multiplied by the sandwich ratio
  (J^-1 K J^-1)_kk / (J^-1)_kk of odohil/science/estimators/scores.py, never
  by less than 1: under misspecification the profile deviance is that ratio
  times a chi^2(1) (Royall 1986), so the interval widens with it.
- **E_R and E_T: Student-t.** estimate +- t quantile x SE, with the
  Satterthwaite degrees of freedom of the standard error itself:
  nu = 2 SE^4 / Var(SE^2), Var(SE^2) by the delta method through the two
  variance rates (SE^2 is a function of K_theta and K_rho, estimated with
  their covariance). A standard error that rests on few effective squares gets
  a wide quantile.

The standard error printed beside every parameter (``stderr``) is the Wald one,
the square root of the diagonal of the inverse expected information at the
estimate (SI). For K_theta and K_rho it is a scale, not the interval: the
interval is the profile one above.
"""

from __future__ import annotations

import math
from collections.abc import Hashable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from odohil.science import distributions
from odohil.science.estimators.joint import JointFit, designs_of
from odohil.science.estimators.likelihood import (
    GroupStats,
    LikelihoodValue,
    ModelPoint,
    StackedGroups,
    evaluate,
    evaluate_arrays,
    nll_many,
)
from odohil.science.paths import FloatArray

FOUR_SIGMA = 4.0
"""The 'confidently wrong' distance, as a normal quantile."""
LEVEL_95 = 0.95
LEVEL_4SIGMA = 0.9999366575163338
"""0.999937: the two-sided level of +- 4 sigma, ``1 - 2 norm_sf(FOUR_SIGMA)``
written out, so that importing this module computes nothing with scipy
(odohil/science/distributions.py; tests/science/test_distributions.py checks it)."""
_LOG_K_RANGE = (math.log(1e-14), math.log(1e2))
_INNER_STEPS = 15
_INNER_TOLERANCE = 1e-3
"""The nuisance re-fit has converged when its Newton decrement (about twice
the NLL still to gain) is below this: the deviance is then exact to about
1e-3, its signed root to about 2.5e-4 at the 95 % level."""
_MAX_LOG_STEP = 2.0
"""Largest change of a nuisance log K in one re-fit step (a factor e^2)."""
_SMALLEST_STEP = 0.05
"""A re-fit step is halved until the NLL does not rise, down to this fraction."""
_HALVINGS = tuple(0.5**j for j in range(8) if 0.5**j > _SMALLEST_STEP)
"""The fractions of a re-fit step tried: 1, 1/2, ..., 1/16."""
_SEARCH_STEPS = 40
_BRACKET_TOLERANCE = 1e-3
"""The search stops when its bracket in log K is this narrow."""
_ROOT_TOLERANCE = 0.01
"""A bound is accepted when |r(psi) - q| is below this (in units of the root)."""
_ROOT_K_SE = 1.0
"""Above an estimate whose Wald standard error of log K exceeds this, the
bound is searched in sqrt(K) (see :meth:`_Profile.bound`)."""


@dataclass(frozen=True)
class Interval:
    """One parameter's interval at the two levels, SI.

    Attributes:
        ci95: the 95 % interval.
        ci_4sigma: the 99.9937 % (4-sigma-equivalent) interval.
        method: how it was formed, for people (e.g. ``profile likelihood
            (Cox-Reid adjusted)``, ``Student t (nu = 14.2)``).
        dof: the t degrees of freedom (None for a profile interval).
    """

    ci95: tuple[float, float]
    ci_4sigma: tuple[float, float]
    method: str
    dof: float | None = None


def t_interval(value: float, stderr: float, dof: float, rule: str) -> Interval:
    """value +- t quantile x stderr at both levels."""
    if not math.isfinite(stderr):
        return Interval((-math.inf, math.inf), (-math.inf, math.inf), rule, dof)
    nu = max(dof, 1.0)
    q95 = distributions.t_ppf(0.5 + LEVEL_95 / 2, nu)
    q4 = distributions.t_ppf(0.5 + LEVEL_4SIGMA / 2, nu)
    return Interval(
        (value - q95 * stderr, value + q95 * stderr),
        (value - q4 * stderr, value + q4 * stderr),
        f"{rule} (nu = {nu:.1f})",
        nu,
    )


def satterthwaite_dof(
    groups: Sequence[GroupStats], fit: JointFit, index: int, cox_reid: bool = True
) -> float:
    """nu = 2 SE^4 / Var(SE^2) of parameter ``index`` (0: E_R, 1: E_T, or
    another mean parameter of the layout), the variance of SE^2 by the delta
    method through the log variance rates (log K_theta and log K_rho, and
    log K_spin where the layout has it)."""
    return satterthwaite_dofs(groups, fit, (index,), cox_reid)[0]


def satterthwaite_dofs(
    groups: Sequence[GroupStats], fit: JointFit, indices: Sequence[int], cox_reid: bool = True
) -> list[float]:
    """:func:`satterthwaite_dof` of several parameters at the cost of one
    (the model is moved once per log rate)."""
    none = [math.inf] * len(indices)
    info = fit.value.information
    if info is None:
        return none
    try:
        cov = np.linalg.inv(info)
    except np.linalg.LinAlgError:
        return none
    wanted = list(indices)
    var = np.diag(cov)[wanted]
    rates = list(fit.point.layout.log_rates)
    grad = np.zeros((len(rates), len(wanted)))
    for j, k in enumerate(rates):
        h, per_log = _rate_step(float(cov[k, k]))
        phi = fit.point.phi.copy()
        phi[k] += h
        moved = evaluate(groups, fit.point.moved(phi, derivatives=True), cox_reid)
        if moved.information is None:
            return none
        try:
            grad[j] = (np.diag(np.linalg.inv(moved.information))[wanted] - var) / per_log
        except np.linalg.LinAlgError:
            return none
    spread = np.einsum("ji,jk,ki->i", grad, cov[np.ix_(rates, rates)], grad)
    out = []
    for v, s2 in zip(var, spread, strict=True):
        ok = v > 0 and math.isfinite(v) and s2 > 0
        out.append(min(2.0 * float(v) ** 2 / float(s2), 1e6) if ok else math.inf)
    return out


_LOG_STEP = 0.05
"""The step in log K of the Satterthwaite derivative for a rate it determines well."""
_K_STEP_SE = 0.1
"""...and, for a rate it does not, the step in K in the rate's standard errors."""


def _rate_step(log_var: float) -> tuple[float, float]:
    """The step h in log K of the derivative of SE^2 in one log rate, and the
    divisor that turns the difference into d SE^2 / d log K at the estimate.

    A rate the data determine (log K's standard error small) is stepped by
    :data:`_LOG_STEP` in log K. A rate on or near its floor has a log K
    variance without bound (issue 19's Create 2 calibrations: K_theta at
    1e-14 rad^2/m, Var(log K) 3.5e17): a step of 0.05 in log K moves K by
    1e-15, below what the information resolves, and the round-off of that
    difference times Var(log K) swamped SE^2's spread (E_T's nu fell to 1,
    its 95 % interval to 12.7 standard errors, its 4-sigma one to +-14). Such
    a rate is stepped by a tenth of its standard error in K instead, and the
    secant in K is taken (d SE^2 / d log K = K d SE^2 / d K = dSE^2 / (e^h - 1)),
    which SE^2's smooth dependence on K makes as good a derivative.
    """
    if not (math.isfinite(log_var) and log_var > 0):
        return _LOG_STEP, _LOG_STEP
    wide = math.log1p(_K_STEP_SE * math.sqrt(log_var))
    if wide <= _LOG_STEP:
        return _LOG_STEP, _LOG_STEP
    h = min(wide, 50.0)  # K at most e^50 times itself: far past any rate's range
    return h, math.expm1(h)


def _with_derivatives(point: ModelPoint, keys: Sequence[Hashable]) -> ModelPoint:
    """``point`` itself when it carries its own derivatives for every key (a
    fit's optimum does), else the model at its phi with derivatives."""
    own = (
        point.d_means is not None
        and point.d_covs is not None
        and np.array_equal(point.anchor, point.phi)
        and all(k in point.d_means and k in point.d_covs for k in keys)
    )
    return point if own else point.model.point(point.phi, keys, derivatives=True)


@dataclass(frozen=True)
class _Solved:
    """One point of the profile: log K, its signed root, the parameters the
    re-fit reached and the likelihood there (for the next warm start)."""

    psi: float
    root: float
    phi: FloatArray
    value: LikelihoodValue


class _Profile:
    """The Cox-Reid adjusted profile NLL of one log K, with warm starts.

    The NLL is that of the model at each point with its derivatives held at
    the estimate (so the Cox-Reid term is the one the fit solved). The
    nuisance re-fit is Newton's method on it with the expected information
    (the derivatives of the log rates rescaled to the point: d/d log K =
    K d/dK), a rate on the floor of log K whose score pushes it down held
    there (as the fit holds it), each step halved until the NLL does not
    rise, until the Newton decrement is below _INNER_TOLERANCE (on the NLL's
    own gradient once a step on the model's score cannot lower it, see
    :meth:`refit`). Each re-fit
    starts from the nearest point of the profile already found, moved along
    the profile's tangent d lambda / d psi = -I_ll^-1 I_l psi; one that does
    not converge is re-fitted from the estimate too and the lower NLL kept."""

    def __init__(
        self, groups: Sequence[GroupStats], fit: JointFit, index: int, cox_reid: bool
    ) -> None:
        self.groups = [g for g in groups if g.n > 0]
        self.designs = designs_of(self.groups)
        self.index = index
        self.layout = fit.point.layout
        self.free = [i for i in range(self.layout.size) if i != index]
        self.rates = list(self.layout.log_rates)
        self.cox_reid = cox_reid
        self.model = fit.point.model
        self.anchor = _with_derivatives(fit.point, self.designs)
        # what every evaluation reads and no evaluation changes: the groups'
        # arrays and the derivatives at the estimate, stacked per group
        self.stack = StackedGroups.of(self.groups)
        anchor = self.anchor
        assert anchor.d_means is not None
        assert anchor.d_covs is not None
        self.d_mu = np.array([anchor.d_means[k] for k in self.stack.keys])  # (G, p, 3)
        self.d_cov = np.array([anchor.d_covs[k] for k in self.stack.keys])  # (G, p, 3, 3)
        self.psi_hat = float(fit.point.phi[index])
        self.evaluations = 0
        self.reference = 0.0
        nll, phi, value, _ = self.refit(self.psi_hat, fit.point.phi)
        self.reference = nll
        self.solved = [_Solved(self.psi_hat, 0.0, phi, value)]

    def _model_arrays(self, phis: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Per point (rows of ``phis``) and group, the model mean and the model
        plus measurement covariance: (Q, G, 3), (Q, G, 3, 3)."""
        means, covs = self.model.moments(phis, self.stack.distinct)
        return self.stack.model_arrays(means, covs)

    def _scaled(self, phis: FloatArray) -> FloatArray:
        """Per row of ``phis`` (Q, p), the factor of each parameter's
        derivatives: K / K_hat for a log rate (d/d log K = K d/dK), else 1."""
        scale = np.ones(phis.shape)
        rates = self.rates
        scale[:, rates] = np.exp(phis[:, rates] - self.anchor.phi[rates])
        return scale

    def _value(self, phi: FloatArray) -> LikelihoodValue:
        """The NLL with its score and information at ``phi`` (the model's
        moments there, its derivatives those at the estimate rescaled to the
        point, see :meth:`_scaled`)."""
        self.evaluations += 1
        mu, cov = self._model_arrays(phi[None])
        scale = self._scaled(phi[None])[0]
        stack = self.stack
        return evaluate_arrays(
            stack.n,
            stack.s,
            stack.t,
            stack.counts,
            mu[0],
            cov[0],
            self.d_mu * scale[:, None],
            self.d_cov * scale[:, None, None],
            self.layout,
            self.cox_reid,
        )

    def _nlls(self, phis: FloatArray) -> FloatArray:
        """The NLL alone at every row of ``phis``, in one batch (the same
        numbers as :meth:`_value`'s)."""
        self.evaluations += len(phis)
        mu, cov = self._model_arrays(phis)
        d_mu = self.d_mu[None] * self._scaled(phis)[:, None, :, None]
        return nll_many(self.stack, mu, cov, d_mu, self.layout, self.cox_reid)

    def _nuisance(self, phi: FloatArray, gradient: FloatArray) -> list[int]:
        """The free parameters not held on the floor (a rate there whose
        score pushes it down)."""
        floor = _LOG_K_RANGE[0] + 1e-9
        return [
            i for i in self.free if not (i in self.rates and phi[i] <= floor and gradient[i] > 0)
        ]

    def _numeric_points(
        self, phi: FloatArray, value: LikelihoodValue
    ) -> tuple[FloatArray, list[float]]:
        """The points of :meth:`_numeric_gradient` (one row per free
        parameter) and their steps: 1e-4 standard errors, at most 1e-3 in log K."""
        assert value.information is not None
        steps = []
        for i in self.free:
            curvature = float(value.information[i, i])
            h = 1e-4 / math.sqrt(curvature) if curvature > 0 else 1e-6
            if i in self.rates:
                h = min(h, 1e-3)
            steps.append(h)
        moved = np.repeat(phi[None], len(self.free), axis=0)
        for row, (i, h) in enumerate(zip(self.free, steps, strict=True)):
            moved[row, i] += h
        return moved, steps

    def _differences(
        self, nlls: FloatArray, steps: list[float], value: LikelihoodValue
    ) -> FloatArray:
        """The forward differences of the NLLs at :meth:`_numeric_points`."""
        out = np.zeros(self.layout.size)
        for row, (i, h) in enumerate(zip(self.free, steps, strict=True)):
            out[i] = (float(nlls[row]) - value.nll) / h
        return out

    def _numeric_gradient(self, phi: FloatArray, value: LikelihoodValue) -> FloatArray:
        """The NLL's own gradient in the free parameters, by forward
        differences of 1e-4 standard errors (at most 1e-3 in log K)."""
        moved, steps = self._numeric_points(phi, value)
        return self._differences(self._nlls(moved), steps, value)

    def refit(
        self, psi: float, start: FloatArray
    ) -> tuple[float, FloatArray, LikelihoodValue, bool]:
        """(profile NLL, the phi reached, the likelihood there, whether the
        re-fit converged) at log K = psi, from ``start``.

        Newton steps on the model's score; once a step cannot lower the NLL
        (that score, with the derivatives held at the estimate, can be off
        far from it), on the NLL's own gradient (:meth:`_numeric_gradient`).
        A step is tried whole, then (if the NLL rose) at every halving down
        to _SMALLEST_STEP at once, the first that does not raise it kept."""
        phi = start.copy()
        phi[self.index] = psi
        phi = self.layout.bounded(phi, *_LOG_K_RANGE)
        value = self._value(phi)
        numeric = False
        ready: FloatArray | None = None  # the numeric gradient at phi, when already known
        for _ in range(_INNER_STEPS):
            if not math.isfinite(value.nll) or value.gradient is None:
                break
            assert value.information is not None
            if not numeric:
                gradient = value.gradient
            elif ready is not None:
                gradient, ready = ready, None
            else:
                gradient = self._numeric_gradient(phi, value)
            free = self._nuisance(phi, gradient)
            g = gradient[free]
            try:
                step = np.linalg.solve(value.information[np.ix_(free, free)], -g)
            except np.linalg.LinAlgError:
                break
            if float(-g @ step) < _INNER_TOLERANCE:
                return value.nll, phi, value, True
            rates = [k for k, i in enumerate(free) if i in self.rates]
            largest = float(np.max(np.abs(step[rates]))) if rates else 0.0
            if largest > _MAX_LOG_STEP:
                step *= _MAX_LOG_STEP / largest
            new = self._stepped(phi, free, step, 1.0)
            trial = self._value(new)
            if not trial.nll <= value.nll + 1e-9:
                shorter = _HALVINGS[1:]
                tried = np.array([self._stepped(phi, free, step, t) for t in shorter])
                if numeric:
                    nlls = self._nlls(tried)
                else:
                    # the numeric gradient at phi rides along: it is what
                    # the next step needs when every halving fails too
                    points, steps = self._numeric_points(phi, value)
                    both = self._nlls(np.concatenate([tried, points]))
                    nlls = both[: len(tried)]
                kept = [j for j, nll in enumerate(nlls) if nll <= value.nll + 1e-9]
                if not kept:
                    if numeric:
                        break
                    numeric = True
                    ready = self._differences(both[len(tried) :], steps, value)
                    continue
                new = tried[kept[0]]
                trial = self._value(new)
            phi, value = new, trial
        return value.nll, phi, value, False

    def _stepped(
        self, phi: FloatArray, free: list[int], step: npt.NDArray[np.floating[Any]], t: float
    ) -> FloatArray:
        """phi moved by t x step in the free parameters, within the bounds."""
        new = phi.copy()
        new[free] += t * step
        return self.layout.bounded(new, *_LOG_K_RANGE)

    def _tangent(self, solved: _Solved) -> FloatArray:
        """d phi / d psi along the profile at a solved point (0 where singular)."""
        out = np.zeros(self.layout.size)
        out[self.index] = 1.0
        info = solved.value.information
        if info is None:
            return out
        assert solved.value.gradient is not None
        free = self._nuisance(solved.phi, solved.value.gradient)
        try:
            slope = np.linalg.solve(info[np.ix_(free, free)], -info[free, self.index])
        except np.linalg.LinAlgError:
            return out
        if np.all(np.isfinite(slope)):
            out[free] = slope
        return out

    def root(self, psi: float) -> float:
        """Signed root of the deviance at psi."""
        near = min(self.solved, key=lambda s: abs(s.psi - psi))
        start = near.phi + (psi - near.psi) * self._tangent(near)
        nll, phi, value, converged = self.refit(psi, start)
        if not converged:
            again = self.refit(psi, self.anchor.phi)
            if again[0] < nll or not math.isfinite(nll):
                nll, phi, value, converged = again
        if not math.isfinite(nll):
            return math.copysign(math.inf, psi - self.psi_hat)
        deviance = max(0.0, 2.0 * (nll - self.reference))
        r = math.copysign(math.sqrt(deviance), psi - self.psi_hat)
        self.solved.append(_Solved(psi, r, phi, value))
        return r

    def _guess(self, q: float, side: float, se_psi: float, root_k: bool) -> float:
        """A first psi for the bound at q on ``side``: the Wald one, or where
        2 g dK + I dK^2 reaches q^2 (score g and efficient information I in K
        at the estimate) for a bound searched in sqrt(K)."""
        wald = self.psi_hat + side * q * se_psi
        first = self.solved[0]
        info, gradient = first.value.information, first.value.gradient
        if not root_k or info is None or gradient is None:
            return wald
        k = self.index
        free = self._nuisance(first.phi, gradient)
        try:
            cross = info[k, free] @ np.linalg.solve(info[np.ix_(free, free)], info[free, k])
        except np.linalg.LinAlgError:
            return wald
        k_hat = math.exp(self.psi_hat)
        i_k = float(info[k, k] - cross) / k_hat**2
        g_k = float(gradient[k]) / k_hat
        if i_k > 0 and math.isfinite(i_k) and math.isfinite(g_k):
            dk = (-g_k + math.sqrt(g_k**2 + i_k * q * q)) / i_k
        elif g_k > 0 and math.isfinite(g_k):
            dk = q * q / (2.0 * g_k)
        else:
            return wald
        return math.log(k_hat + dk) if dk > 0 else wald

    def bound(self, q: float, side: float, se_psi: float) -> float:
        """The psi on ``side`` (+1 or -1) where the signed root is side x q;
        inf (open) when it is not reached within the range of log K.

        A safeguarded secant search on r in x = psi or, above an estimate on
        the floor or with a Wald interval wider than a factor
        e^(2 _ROOT_K_SE) (where the deviance grows like K, not like log K),
        in x = sqrt(K) = exp(psi / 2). The first x comes from
        :meth:`_guess` (or, for the second level, from the points the first
        found); then the secant through the two points nearest the level,
        kept inside the bracket of the points short of it and past it
        (bisection when it leaves it; doubling the distance from the estimate
        while nothing is past it)."""
        limit = _LOG_K_RANGE[1] if side > 0 else _LOG_K_RANGE[0]
        if (limit - self.psi_hat) * side <= 1e-9:
            return side * math.inf
        root_k = side > 0 and (self.psi_hat <= _LOG_K_RANGE[0] + 1e-9 or se_psi > _ROOT_K_SE)

        def to_x(psi: float) -> float:
            return math.exp(0.5 * psi) if root_k else psi

        def to_psi(x: float) -> float:
            return 2.0 * math.log(x) if root_k else x

        target = side * q
        x_hat, x_limit = to_x(self.psi_hat), to_x(limit)
        points = [(to_x(s.psi), s.root) for s in self.solved if (s.psi - self.psi_hat) * side >= 0]
        x = to_x(float(np.clip(self._guess(q, side, se_psi, root_k), *_LOG_K_RANGE)))
        for step in range(_SEARCH_STEPS):
            short = [p for p in points if (p[1] - target) * side < 0]
            past = [p for p in points if not (p[1] - target) * side < 0]
            inner = max(short, key=lambda p: side * p[0])[0]
            outer = min(past, key=lambda p: side * p[0])[0] if past else None
            if outer is not None and abs(to_psi(outer) - to_psi(inner)) < _BRACKET_TOLERANCE:
                return to_psi(0.5 * (inner + outer))
            if step > 0 or len(points) > 1:
                x = _next_x(points, target, side, inner, outer, x_hat, x_limit)
            r = self.root(to_psi(x))
            if abs(r - target) < _ROOT_TOLERANCE:
                return to_psi(x)
            if x == x_limit and (r - target) * side < 0:
                return side * math.inf
            points.append((x, r if math.isfinite(r) else side * math.inf))
        short = [p for p in points if (p[1] - target) * side < 0]
        past = [p for p in points if not (p[1] - target) * side < 0]
        if not past:
            return side * math.inf
        return to_psi(min(past, key=lambda p: side * p[0])[0])


def _next_x(
    points: list[tuple[float, float]],
    target: float,
    side: float,
    inner: float,
    outer: float | None,
    x_hat: float,
    x_limit: float,
) -> float:
    """The next x of :meth:`_Profile.bound`'s search: the secant through the
    two finite points nearest the level when it rises toward ``side`` and
    falls strictly inside the bracket (inner, outer), else the bracket's
    middle, else (nothing past the level yet) twice inner's distance from
    the estimate, at most the end of the range."""
    high = outer if outer is not None else x_limit
    finite = [p for p in points if math.isfinite(p[1])]
    near = sorted(finite, key=lambda p: abs(p[1] - target))[:2]
    if len(near) == 2 and near[0][0] != near[1][0]:
        (xa, ra), (xb, rb) = near
        slope = (rb - ra) / (xb - xa)
        if slope > 0:
            x = xb + (target - rb) / slope
            if (x - inner) * side > 0 and (high - x) * side > 0:
                return x
            if outer is None and (x - inner) * side > 0:
                return x_limit
    if outer is not None:
        return 0.5 * (inner + outer)
    x = inner + 2.0 * (inner - x_hat)
    return x if (x_limit - x) * side > 0 else x_limit


def profile_interval(
    groups: Sequence[GroupStats],
    fit: JointFit,
    index: int,
    cox_reid: bool = True,
    widen: float = 1.0,
) -> Interval:
    """The profile-likelihood interval of K_theta (index 2) or K_rho (3), or
    another log rate of the layout (K_spin), at both levels (see the module
    docstring), SI. ``widen`` (at least 1) multiplies the deviance threshold: the sandwich ratio of
    odohil/science/estimators/scores.py when the data spread more than the
    model says."""
    widen = max(widen, 1.0) if math.isfinite(widen) else 1.0
    profile = _Profile(groups, fit, index, cox_reid)
    info = fit.value.information
    se_psi = math.inf
    if info is not None:
        try:
            se_psi = math.sqrt(max(float(np.linalg.inv(info)[index, index]), 0.0))
        except np.linalg.LinAlgError:
            se_psi = math.inf
    if not math.isfinite(se_psi) or se_psi == 0:
        se_psi = 1.0
    ends: list[tuple[float, float]] = []
    for level_q in (distributions.norm_isf((1 - LEVEL_95) / 2), FOUR_SIGMA):
        q = level_q * math.sqrt(widen)
        low = profile.bound(q, -1.0, se_psi)
        high = profile.bound(q, 1.0, se_psi)
        ends.append((_exp(low), _exp(high)))
    rule = "profile likelihood (Cox-Reid adjusted)"
    if widen > 1.0:
        rule = f"profile likelihood (Cox-Reid adjusted, widened by the sandwich ratio {widen:.2f})"
    return Interval(ends[0], ends[1], rule)


def _exp(psi: float) -> float:
    if psi == -math.inf or psi <= _LOG_K_RANGE[0]:
        return 0.0
    if psi == math.inf:
        return math.inf
    return math.exp(psi)
