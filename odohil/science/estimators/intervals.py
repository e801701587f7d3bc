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
  parameters re-fitted with psi held. The end points are found by a secant
  search on the signed root r(psi) = sign(psi - psi_hat) sqrt(D), nearly
  linear in psi. The nuisance re-fit is Fisher scoring with the model's
  derivatives taken at the estimate (the moments, hence the likelihood, are
  exact at every point). A bound the deviance never reaches within the
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
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy import stats

from odohil.science.estimators.joint import JointFit, designs_of
from odohil.science.estimators.likelihood import (
    GroupStats,
    LikelihoodValue,
    ModelPoint,
    evaluate,
    with_moments,
)
from odohil.science.paths import FloatArray

FOUR_SIGMA = 4.0
"""The 'confidently wrong' distance, as a normal quantile."""
LEVEL_95 = 0.95
LEVEL_4SIGMA = 1.0 - 2.0 * float(stats.norm.sf(FOUR_SIGMA))
"""0.999937: the two-sided level of +- 4 sigma."""
_LOG_K_RANGE = (math.log(1e-14), math.log(1e2))
_INNER_STEPS = 8
_INNER_TOLERANCE = 1e-6
"""The nuisance re-fit stops when its Newton decrement (about twice the NLL
still to gain) is below this."""
_SECANT_STEPS = 8
_BISECTION_STEPS = 40
_BRACKET_TOLERANCE = 1e-3
"""Bisection stops when the bracket in log K is this narrow."""
_ROOT_TOLERANCE = 0.01
"""A bound is accepted when |r(psi) - q| is below this (in units of the root)."""


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
    q95 = float(stats.t.ppf(0.5 + LEVEL_95 / 2, nu))
    q4 = float(stats.t.ppf(0.5 + LEVEL_4SIGMA / 2, nu))
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
    h = 0.05
    grad = np.zeros((len(rates), len(wanted)))
    for j, k in enumerate(rates):
        phi = fit.point.phi.copy()
        phi[k] += h
        moved = evaluate(groups, fit.point.moved(phi, derivatives=True), cox_reid)
        if moved.information is None:
            return none
        try:
            grad[j] = (np.diag(np.linalg.inv(moved.information))[wanted] - var) / h
        except np.linalg.LinAlgError:
            return none
    spread = np.einsum("ji,jk,ki->i", grad, cov[np.ix_(rates, rates)], grad)
    out = []
    for v, s2 in zip(var, spread, strict=True):
        ok = v > 0 and math.isfinite(v) and s2 > 0
        out.append(min(2.0 * float(v) ** 2 / float(s2), 1e6) if ok else math.inf)
    return out


class _Profile:
    """The Cox-Reid adjusted profile NLL of one log K, with warm starts."""

    def __init__(
        self, groups: Sequence[GroupStats], fit: JointFit, index: int, cox_reid: bool
    ) -> None:
        self.groups = [g for g in groups if g.n > 0]
        self.designs = designs_of(self.groups)
        self.index = index
        self.layout = fit.point.layout
        self.free = [i for i in range(self.layout.size) if i != index]
        self.cox_reid = cox_reid
        self.model = fit.point.model
        self.anchor: ModelPoint = self.model.point(fit.point.phi, self.designs, derivatives=True)
        self.psi_hat = float(fit.point.phi[index])
        self.evaluations = 0
        base = self.refit(self.psi_hat, fit.point.phi)
        self.reference = base[0]
        self.last = fit.point.phi.copy()

    def _value(self, phi: FloatArray) -> LikelihoodValue:
        point = with_moments(self.anchor, self.model.point(phi, self.designs, derivatives=False))
        return evaluate(self.groups, point, self.cox_reid)

    def refit(self, psi: float, start: FloatArray) -> tuple[float, FloatArray]:
        """(profile NLL, the phi reached) at log K = psi, from ``start``."""
        phi = start.copy()
        phi[self.index] = psi
        value = self._value(phi)
        if not math.isfinite(value.nll):
            return math.inf, phi
        free = self.free
        for _ in range(_INNER_STEPS):
            self.evaluations += 1
            if value.gradient is None or value.information is None:
                break
            g = value.gradient[free]
            info = value.information[np.ix_(free, free)]
            try:
                step = np.linalg.solve(info, -g)
            except np.linalg.LinAlgError:
                break
            if float(-g @ step) < _INNER_TOLERANCE:
                break
            t = 1.0
            while t > 0.05:
                new = phi.copy()
                new[free] += t * step
                new[free] = self.layout.bounded(new, *_LOG_K_RANGE)[free]
                trial = self._value(new)
                if trial.nll <= value.nll + 1e-9:
                    break
                t /= 2.0
            else:
                break
            phi, value = new, trial
        return value.nll, phi

    def root(self, psi: float) -> float:
        """Signed root of the deviance at psi. The re-fit starts from the last
        point; when that gives a deviance above 1 it is re-fitted from the
        estimate too and the lower one kept (a warm start far from psi's own
        optimum can stop, after its few steps, well above it: the deviance
        then jumps about and the bound lands almost on the estimate)."""
        nll, phi = self.refit(psi, self.last)
        if not (math.isfinite(nll) and 2.0 * (nll - self.reference) <= 1.0):
            again, other = self.refit(psi, self.anchor.phi)
            if again < nll or not math.isfinite(nll):
                nll, phi = again, other
        if not math.isfinite(nll):
            return math.copysign(math.inf, psi - self.psi_hat)
        self.last = phi
        deviance = max(0.0, 2.0 * (nll - self.reference))
        return math.copysign(math.sqrt(deviance), psi - self.psi_hat)

    def bound(self, q: float, side: float, guess: float) -> float:
        """The psi on ``side`` (+1 or -1) where the signed root is side x q;
        inf (open) when it is not reached within the range of log K."""
        limit = _LOG_K_RANGE[1] if side > 0 else _LOG_K_RANGE[0]
        self.last = self.anchor.phi.copy()
        target = side * q
        a, ra = self.psi_hat, 0.0
        b = self.psi_hat + side * max(abs(guess), 1e-6)
        inner, outer = self.psi_hat, math.nan  # the bracket: short of the target, past it
        for _ in range(_SECANT_STEPS):
            b = float(np.clip(b, *_LOG_K_RANGE))
            rb = self.root(b)
            if abs(rb - target) < _ROOT_TOLERANCE:
                return b
            if b == limit and (rb - target) * side < 0:
                return side * math.inf
            if math.isfinite(rb):
                if (rb - target) * side < 0:
                    inner = b if (b - inner) * side > 0 else inner
                elif math.isnan(outer) or (outer - b) * side > 0:
                    outer = b
            if not math.isfinite(rb) or (rb - ra) * (b - a) <= 0:
                # r must rise with psi: step half-way back toward the last good point
                b = 0.5 * (a + b)
                continue
            slope = (rb - ra) / (b - a)
            a, ra, b = b, rb, b + (target - rb) / slope
        return self._bisect(target, side, inner, outer, limit)

    def _bisect(
        self, target: float, side: float, inner: float, outer: float, limit: float
    ) -> float:
        """Bisection on the bracket [inner, outer] when the secant did not
        converge (r far from linear in psi: an estimate at the floor of log K,
        where the deviance grows like K = e^psi)."""
        if math.isnan(outer):
            if (self.root(limit) - target) * side < 0:
                return side * math.inf
            outer = limit
        middle = 0.5 * (inner + outer)
        for _ in range(_BISECTION_STEPS):
            middle = 0.5 * (inner + outer)
            r = self.root(middle)
            if abs(r - target) < _ROOT_TOLERANCE or abs(outer - inner) < _BRACKET_TOLERANCE:
                return middle
            if math.isfinite(r) and (r - target) * side < 0:
                inner = middle
            else:
                outer = middle
        return middle


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
    for level_q in (float(stats.norm.isf((1 - LEVEL_95) / 2)), FOUR_SIGMA):
        q = level_q * math.sqrt(widen)
        low = profile.bound(q, -1.0, q * se_psi)
        high = profile.bound(q, 1.0, q * se_psi)
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
