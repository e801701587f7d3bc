"""The Gaussian likelihood of grouped trials, its score and Fisher information.

Each trial's v = (x, y, Delta) is modelled as N(mu_d, Sigma_d + C): the model's
exact mean and covariance for its design d
(:func:`odohil.science.moments.pose_moments`) plus the trial's measurement
covariance C. The parameters are handled as

    phi = (E_R rad/m, E_T, log K_theta, log K_rho)

so that the variance rates stay positive and their errors are relative.
For a group of n trials with sums s = sum v and T = sum v v^T (and
R = T - s mu^T - mu s^T + n mu mu^T):

    NLL   = 1/2 [n log det S + tr(S^-1 R)] + 3n/2 log 2 pi
    dNLL  = -dmu^T S^-1 (s - n mu) + 1/2 tr(S^-1 dS (n I - S^-1 R))
    I     = n [dmu_a^T S^-1 dmu_b + 1/2 tr(S^-1 dS_a S^-1 dS_b)]

(the last is the expected information, used as the Hessian in Fisher scoring).

Weighted groups (the robust fit's M-step, :mod:`odohil.science.estimators.robust`)
replace s, T and the n of the quadratic terms and of the information by their
weighted versions W = sum w; log det S keeps the count n.

Cox-Reid adjustment (``cox_reid=True``): the NLL gains 1/2 log det I_bb, the
information of the mean parameters b = (E_R, E_T) (its mean part,
sum W dmu_b^T S^-1 dmu_c). Its derivative in log K_theta and log K_rho,
-1/2 tr(I_bb^-1 sum W dmu^T S^-1 dS_a S^-1 dmu), is added to the score (second
derivatives of the model are neglected, and the term's dependence on b is
taken as 0). This is the adjusted profile likelihood of Cox and Reid (1987)
for the variance rates with the mean parameters as nuisance; like REML it
removes most of the small-sample downward bias of K_theta and K_rho.

Other models. Everything here, in :mod:`~odohil.science.estimators.joint` and
in :mod:`~odohil.science.estimators.intervals` works on any parameter vector
phi described by a :class:`Layout` (which entries are log variance rates, which
are the mean parameters of the Cox-Reid adjustment) and any moments keyed by
a hashable key (a :class:`MomentModel`). The default, :data:`DESIGN_MODEL`, is
the four-parameter model of forth-and-back designs keyed by
:class:`~odohil.science.paths.Design`; the general-path model with turn errors
(:mod:`odohil.science.estimators.paths`) keys each trial by its number and adds
e_turn and log K_spin.
"""

from __future__ import annotations

import math
from collections.abc import Hashable, Iterable, Sequence
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Protocol

import numpy as np

from odohil.science.estimators.observations import align_heading
from odohil.science.fisher import many_moment_derivatives
from odohil.science.moments import BATCH_COLUMNS, PathSet, batch_moments
from odohil.science.parameters import PARAMETER_NAMES, ErrorParameters
from odohil.science.paths import Design, EncoderPath, FloatArray
from odohil.units import wrap_angles

_LOG_2PI = math.log(2.0 * math.pi)


@dataclass(frozen=True)
class Layout:
    """What each entry of a parameter vector phi is.

    Attributes:
        names: the parameters' names, in order (SI values are phi, or exp(phi)
            for the log rates).
        log_rates: indices of the variance rates, held as their logarithms.
        mean_index: indices of the mean parameters (the nuisance parameters of
            the Cox-Reid adjustment).
        floors: (index, lowest value) of the other parameters with a bound
            (1 + E_T and 1 + e_turn stay positive).
    """

    names: tuple[str, ...]
    log_rates: tuple[int, ...]
    mean_index: tuple[int, ...]
    floors: tuple[tuple[int, float], ...] = ()

    @property
    def size(self) -> int:
        """Number of parameters."""
        return len(self.names)

    def to_si(self, phi: FloatArray) -> FloatArray:
        """The SI values of phi (exp of the log rates)."""
        out = np.array(phi, dtype=np.float64)
        out[list(self.log_rates)] = np.exp(out[list(self.log_rates)])
        return out

    def jacobian(self, phi: FloatArray) -> FloatArray:
        """d(SI values)/d(phi), diagonal."""
        scale = np.ones(self.size)
        rates = list(self.log_rates)
        scale[rates] = np.exp(np.asarray(phi, dtype=np.float64)[rates])
        return np.diag(scale)

    def bounded(self, phi: FloatArray, low: float, high: float) -> FloatArray:
        """phi with the log rates clipped to [low, high] and the floors applied."""
        out = np.array(phi, dtype=np.float64)
        rates = list(self.log_rates)
        out[rates] = np.clip(out[rates], low, high)
        for index, floor in self.floors:
            out[index] = max(out[index], floor)
        return out


FOUR_PARAMETERS = Layout(PARAMETER_NAMES, (2, 3), (0, 1), ((1, -0.99),))
"""phi = (E_R rad/m, E_T, log K_theta, log K_rho): the paper's model."""


class GroupStats(Protocol):
    """What the likelihood needs of a group of trials that share their model
    moments and measurement covariance (:class:`~odohil.science.estimators.observations.TrialGroup`
    for designs, one trial each for general paths)."""

    @property
    def key(self) -> Hashable:
        """The key of the group's moments in a :class:`ModelPoint`."""
        ...

    @property
    def reference(self) -> float:
        """The heading the group's Delta are unwrapped near, rad."""
        ...

    @property
    def n(self) -> int:
        """Number of trials."""
        ...

    @property
    def weight(self) -> float:
        """Sum of the trials' weights."""
        ...

    @property
    def total(self) -> FloatArray:
        """Weighted sum of v, (3,)."""
        ...

    @property
    def outer(self) -> FloatArray:
        """Weighted sum of v v^T, (3, 3)."""
        ...

    @property
    def measurement_cov(self) -> FloatArray:
        """Mean measurement covariance, (3, 3)."""
        ...


class MomentModel(Protocol):
    """Moments (and their phi-derivatives) of every key at a phi."""

    @property
    def layout(self) -> Layout:
        """The parameter vector's layout."""
        ...

    def point(self, phi: FloatArray, keys: Iterable[Hashable], derivatives: bool) -> ModelPoint:
        """The model at ``phi`` for ``keys``, with derivatives if asked."""
        ...

    def moments(self, phis: FloatArray, keys: Sequence[Hashable]) -> tuple[FloatArray, FloatArray]:
        """The moments of ``keys`` at every row of ``phis`` (Q, p) in one batch:
        means (Q, K, 3) and covariances (Q, K, 3, 3), each row the same numbers
        as :meth:`point` gives at that phi (SI)."""
        ...


class _DesignModel:
    """The four-parameter model of forth-and-back designs (keys: :class:`Design`)."""

    @property
    def layout(self) -> Layout:
        return FOUR_PARAMETERS

    def point(self, phi: FloatArray, keys: Iterable[Hashable], derivatives: bool) -> ModelPoint:
        designs = [k for k in keys if isinstance(k, Design)]
        return model_point(phi, designs, derivatives)

    def moments(self, phis: FloatArray, keys: Sequence[Hashable]) -> tuple[FloatArray, FloatArray]:
        designs = tuple(k for k in keys if isinstance(k, Design))
        rows = np.zeros((len(phis), len(BATCH_COLUMNS)))
        for row, phi in zip(rows, phis, strict=True):
            row[:4] = from_phi(phi).as_tuple()
        return batch_moments(design_paths(designs), rows)


DESIGN_MODEL: MomentModel = _DesignModel()
"""The default model: :func:`model_point` of forth-and-back designs."""


def to_phi(params: ErrorParameters) -> FloatArray:
    """(E_R, E_T, log K_theta, log K_rho) of positive-rate parameters."""
    return np.array([params.e_r, params.e_t, math.log(params.k_theta), math.log(params.k_rho)])


def from_phi(phi: FloatArray) -> ErrorParameters:
    """The parameters (SI) of phi = (E_R, E_T, log K_theta, log K_rho)."""
    return ErrorParameters(
        float(phi[0]), float(phi[1]), math.exp(float(phi[2])), math.exp(float(phi[3]))
    )


@dataclass(frozen=True)
class ModelPoint:
    """The model's moments of every design (key) at one phi, with derivatives in phi.

    Attributes:
        phi: (p,) the point (p = 4 for :data:`FOUR_PARAMETERS`).
        means: per key, (3,) mean of v.
        covs: per key, (3, 3) model covariance of v.
        d_means: per key, (p, 3) d mean / d phi (None when not computed).
        d_covs: per key, (p, 3, 3) d cov / d phi (None when not computed).
        anchor: the phi where the derivatives were evaluated (``phi`` unless
            they were carried over from a nearby point by :func:`with_moments`).
        model: the model that made it (to move to another phi).
    """

    phi: FloatArray
    means: dict[Hashable, FloatArray]
    covs: dict[Hashable, FloatArray]
    d_means: dict[Hashable, FloatArray] | None
    d_covs: dict[Hashable, FloatArray] | None
    anchor: FloatArray
    model: MomentModel = field(default=DESIGN_MODEL, repr=False, compare=False)

    @property
    def layout(self) -> Layout:
        """The parameter vector's layout."""
        return self.model.layout

    def moved(self, phi: FloatArray, derivatives: bool) -> ModelPoint:
        """The same model at another phi, for the same keys."""
        return self.model.point(phi, list(self.means), derivatives)


def with_moments(point: ModelPoint, moved: ModelPoint) -> ModelPoint:
    """``moved``'s phi and moments with ``point``'s derivatives (and anchor)."""
    return ModelPoint(
        moved.phi,
        moved.means,
        moved.covs,
        point.d_means,
        point.d_covs,
        point.anchor,
        moved.model,
    )


@lru_cache(maxsize=64)
def design_path(design: Design) -> EncoderPath:
    """The design's encoder path (immutable; building it costs as much as the moments)."""
    return design.path()


@lru_cache(maxsize=64)
def design_paths(designs: tuple[Design, ...]) -> PathSet:
    """The designs' encoder paths as one padded set (immutable, so cached)."""
    return PathSet.of(tuple(design_path(design) for design in designs))


def model_point(phi: FloatArray, designs: Iterable[Design], derivatives: bool) -> ModelPoint:
    """Evaluate the moments (and, if asked, their phi-derivatives) of each design,
    every design (and finite-difference point) in one batch."""
    params = from_phi(phi)
    chosen = tuple(designs)
    means: dict[Hashable, FloatArray] = {}
    covs: dict[Hashable, FloatArray] = {}
    d_means: dict[Hashable, FloatArray] = {}
    d_covs: dict[Hashable, FloatArray] = {}
    if chosen and derivatives:
        scale = np.array([1.0, 1.0, params.k_theta, params.k_rho])
        derivatives_of = many_moment_derivatives(design_paths(chosen), params)
        for design, d in zip(chosen, derivatives_of, strict=True):
            means[design], covs[design] = d.mean, d.cov
            d_means[design] = d.d_mean * scale[:, None]
            d_covs[design] = d.d_cov * scale[:, None, None]
    elif chosen:
        row = np.zeros((1, len(BATCH_COLUMNS)))
        row[0, :4] = params.as_tuple()
        batch_means, batch_covs = batch_moments(design_paths(chosen), row)
        for i, design in enumerate(chosen):
            means[design], covs[design] = batch_means[0, i], batch_covs[0, i]
    here = np.array(phi, dtype=np.float64)
    return ModelPoint(
        here,
        means,
        covs,
        d_means if derivatives else None,
        d_covs if derivatives else None,
        here,
    )


@dataclass(frozen=True)
class LikelihoodValue:
    """Negative log-likelihood at a point, with score and information if derivatives exist.

    Attributes:
        nll: negative log-likelihood (inf where a covariance is singular).
        gradient: (p,) d NLL / d phi, or None.
        information: (p, p) expected Fisher information in phi, or None.
    """

    nll: float
    gradient: FloatArray | None
    information: FloatArray | None


def _stack(groups: Sequence[GroupStats], point: ModelPoint) -> tuple[FloatArray, ...]:
    n = np.array([g.weight for g in groups], dtype=np.float64)
    s = np.array([g.total for g in groups])
    t = np.array([g.outer for g in groups])
    mu = np.array([align_heading(point.means[g.key], g.reference) for g in groups])
    cov = np.array([point.covs[g.key] + g.measurement_cov for g in groups])
    return n, s, t, mu, cov


def evaluate(
    groups: Sequence[GroupStats],
    point: ModelPoint,
    cox_reid: bool = False,
    nll_only: bool = False,
) -> LikelihoodValue:
    """NLL of the grouped trials at ``point``; score and information too when
    ``point`` carries derivatives. ``cox_reid``: the adjusted NLL (see the
    module docstring; needs derivatives, else the plain NLL is returned).
    ``nll_only``: the same NLL (the same operations, so the same number)
    without the score and information (None), for a caller that differences
    NLLs (odohil/science/estimators/intervals.py)."""
    groups = [g for g in groups if g.n > 0]
    n, s, t, mu, cov = _stack(groups, point)
    counts = np.array([g.n for g in groups], dtype=np.float64)
    d_mu = d_cov = None
    if point.d_means is not None and point.d_covs is not None:
        d_mu = np.array([point.d_means[g.key] for g in groups])  # (G, p, 3)
        if not nll_only:
            d_cov = np.array([point.d_covs[g.key] for g in groups])  # (G, p, 3, 3)
    return evaluate_arrays(n, s, t, counts, mu, cov, d_mu, d_cov, point.layout, cox_reid)


def evaluate_arrays(
    n: FloatArray,
    s: FloatArray,
    t: FloatArray,
    counts: FloatArray,
    mu: FloatArray,
    cov: FloatArray,
    d_mu: FloatArray | None,
    d_cov: FloatArray | None,
    layout: Layout,
    cox_reid: bool,
) -> LikelihoodValue:
    """:func:`evaluate` on its stacked arrays (G groups): weights ``n``, sums
    ``s`` (G, 3) and ``t`` (G, 3, 3), counts, model means ``mu`` (G, 3)
    (Delta near the group's reference) and covariances ``cov`` (G, 3, 3)
    with the measurement's, and the derivatives ``d_mu`` (G, p, 3) and
    ``d_cov`` (G, p, 3, 3): the NLL alone when ``d_mu`` is None, with the
    Cox-Reid term but no score when ``d_cov`` is None."""
    cov = 0.5 * (cov + np.swapaxes(cov, 1, 2))
    sign, logdet = np.linalg.slogdet(cov)
    if np.any(sign <= 0) or not np.all(np.isfinite(logdet)):
        return LikelihoodValue(math.inf, None, None)
    inv = np.linalg.inv(cov)
    r = (
        t
        - np.einsum("gi,gj->gij", s, mu)
        - np.einsum("gi,gj->gij", mu, s)
        + n[:, None, None] * np.einsum("gi,gj->gij", mu, mu)
    )
    inv_r = np.einsum("gij,gjk->gik", inv, r)
    nll = 0.5 * float(
        (counts * logdet).sum() + np.einsum("gii->", inv_r) + 3.0 * counts.sum() * _LOG_2PI
    )
    if d_mu is None:
        return LikelihoodValue(nll, None, None)
    if d_cov is None:
        if cox_reid:
            mean_index = list(layout.mean_index)
            mean_info = np.einsum("g,gai,gij,gbj->ab", n, d_mu, inv, d_mu)
            half_logdet = _half_logdet(mean_info[np.ix_(mean_index, mean_index)])
            if half_logdet is not None:
                nll += half_logdet
        return LikelihoodValue(nll, None, None)
    resid = s - n[:, None] * mu
    w = np.einsum("gij,gajk->gaik", inv, d_cov)  # S^-1 dS_a
    grad = (
        -np.einsum("gai,gij,gj->a", d_mu, inv, resid)
        + 0.5 * np.einsum("g,gaii->a", counts, w)
        - 0.5 * np.einsum("gaij,gji->a", w, inv_r)
    )
    mean_info = np.einsum("g,gai,gij,gbj->ab", n, d_mu, inv, d_mu)
    info = mean_info + 0.5 * np.einsum("g,gaij,gbji->ab", n, w, w)
    if cox_reid:
        mean_index = list(layout.mean_index)
        adjustment = _cox_reid(
            mean_info[np.ix_(mean_index, mean_index)],
            n,
            d_mu,
            np.asarray(inv, np.float64),
            w,
            layout,
        )
        if adjustment is not None:
            nll += adjustment[0]
            grad = grad + adjustment[1]
    return LikelihoodValue(nll, grad, 0.5 * (info + info.T))


@dataclass(frozen=True)
class StackedGroups:
    """Groups (those with trials) as the arrays :func:`evaluate_arrays` reads,
    for a caller that evaluates one set of groups at many points.

    Attributes:
        keys: per group, the key of its moments.
        slot: per group, the index of its key in ``distinct``.
        distinct: the distinct keys, in order.
        n: (G,) weights; s: (G, 3) and t: (G, 3, 3) weighted sums of v and v v^T;
        counts: (G,) numbers of trials; measurement: (G, 3, 3) covariances;
        reference: (G,) headings Delta is unwrapped near, rad.
    """

    keys: tuple[Hashable, ...]
    slot: tuple[int, ...]
    distinct: tuple[Hashable, ...]
    n: FloatArray
    s: FloatArray
    t: FloatArray
    counts: FloatArray
    measurement: FloatArray
    reference: FloatArray

    @classmethod
    def of(cls, groups: Sequence[GroupStats]) -> StackedGroups:
        """The arrays of ``groups`` (those with n > 0)."""
        kept = [g for g in groups if g.n > 0]
        keys = tuple(g.key for g in kept)
        distinct = tuple(dict.fromkeys(keys))
        where = {k: i for i, k in enumerate(distinct)}
        return cls(
            keys,
            tuple(where[k] for k in keys),
            distinct,
            np.array([g.weight for g in kept], dtype=np.float64),
            np.array([g.total for g in kept]),
            np.array([g.outer for g in kept]),
            np.array([g.n for g in kept], dtype=np.float64),
            np.array([g.measurement_cov for g in kept]),
            np.array([g.reference for g in kept], dtype=np.float64),
        )

    def model_arrays(self, means: FloatArray, covs: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Per group, the model mean (Delta near its reference) and the model
        plus measurement covariance, from the moments of :attr:`distinct`
        (means (..., K, 3), covs (..., K, 3, 3)): (..., G, 3) and (..., G, 3, 3),
        the numbers :func:`evaluate` stacks."""
        slot = list(self.slot)
        mu = means[..., slot, :].copy()
        mu[..., 2] = self.reference + wrap_angles(mu[..., 2] - self.reference)
        return mu, covs[..., slot, :, :] + self.measurement


def nll_many(
    stack: StackedGroups,
    mu: FloatArray,
    cov: FloatArray,
    d_mu: FloatArray | None,
    layout: Layout,
    cox_reid: bool,
) -> FloatArray:
    """The NLL of :func:`evaluate` at Q points at once, the same operations
    (so the same numbers) on a leading axis: ``mu`` (Q, G, 3) and ``cov``
    (Q, G, 3, 3) as :meth:`StackedGroups.model_arrays` gives them, ``d_mu``
    (Q, G, p, 3) the derivatives of the means (for the Cox-Reid term, with
    ``cox_reid``; None: no term). inf where a covariance is singular."""
    n, s, t, counts = stack.n, stack.s, stack.t, stack.counts
    cov = 0.5 * (cov + np.swapaxes(cov, -1, -2))
    sign, logdet = np.linalg.slogdet(cov)
    bad = np.any(sign <= 0, axis=-1) | ~np.all(np.isfinite(logdet), axis=-1)
    if np.any(bad):
        cov = cov.copy()
        cov[bad] = np.eye(3)
    inv = np.linalg.inv(cov)
    r = (
        t
        - np.einsum("gi,qgj->qgij", s, mu)
        - np.einsum("qgi,gj->qgij", mu, s)
        + n[:, None, None] * np.einsum("qgi,qgj->qgij", mu, mu)
    )
    inv_r = np.einsum("qgij,qgjk->qgik", inv, r)
    weighted = counts * logdet
    constant = 3.0 * counts.sum() * _LOG_2PI
    mean_index = list(layout.mean_index)
    nll = np.full(len(mu), math.inf)
    for q in np.flatnonzero(~bad):
        # the sums over the groups one point at a time, as evaluate does them
        # (a sum over a (Q, G) array's rows can round differently)
        nll[q] = 0.5 * float(weighted[q].sum() + np.einsum("gii->", inv_r[q]) + constant)
        if cox_reid and d_mu is not None:
            mean_info = np.einsum("g,gai,gij,gbj->ab", n, d_mu[q], inv[q], d_mu[q])
            half_logdet = _half_logdet(mean_info[np.ix_(mean_index, mean_index)])
            if half_logdet is not None:
                nll[q] += half_logdet
    return nll


def _cox_reid(
    info_bb: FloatArray,
    n: FloatArray,
    d_mu: FloatArray,
    inv: FloatArray,
    w: FloatArray,
    layout: Layout = FOUR_PARAMETERS,
) -> tuple[float, FloatArray] | None:
    """(1/2 log det I_bb, its gradient in phi), or None when I_bb is singular."""
    half_logdet = _half_logdet(info_bb)
    if half_logdet is None:
        return None
    inv_bb = np.linalg.inv(info_bb)
    # d I_bb / d phi_a = -sum W dmu_b^T S^-1 dS_a S^-1 dmu_c, for a = the log rates
    mean_index = list(layout.mean_index)
    rates = list(layout.log_rates)
    d_b = d_mu[:, mean_index]
    d_info = -np.einsum("g,gbi,gaij,gjk,gck->abc", n, d_b, w[:, rates], inv, d_b)
    grad = np.zeros(d_mu.shape[1])
    grad[rates] = 0.5 * np.einsum("bc,acb->a", inv_bb, d_info)
    return half_logdet, grad


def _half_logdet(info_bb: FloatArray) -> float | None:
    """1/2 log det I_bb, or None when I_bb is singular."""
    sign, logdet = np.linalg.slogdet(info_bb)
    if sign <= 0 or not math.isfinite(logdet):
        return None
    return 0.5 * float(logdet)
