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
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from odohil.science.estimators.observations import TrialGroup, align_heading
from odohil.science.fisher import moment_derivatives
from odohil.science.moments import pose_moments
from odohil.science.parameters import ErrorParameters
from odohil.science.paths import Design, EncoderPath, FloatArray

_LOG_2PI = math.log(2.0 * math.pi)


def to_phi(params: ErrorParameters) -> FloatArray:
    """(E_R, E_T, log K_theta, log K_rho) of positive-rate parameters."""
    return np.array([params.e_r, params.e_t, math.log(params.k_theta), math.log(params.k_rho)])


def from_phi(phi: FloatArray) -> ErrorParameters:
    """The parameters (SI) of phi = (E_R, E_T, log K_theta, log K_rho)."""
    return ErrorParameters(
        float(phi[0]), float(phi[1]), math.exp(float(phi[2])), math.exp(float(phi[3]))
    )


def phi_jacobian(params: ErrorParameters) -> FloatArray:
    """d(SI parameters)/d(phi): diag(1, 1, K_theta, K_rho)."""
    return np.diag([1.0, 1.0, params.k_theta, params.k_rho])


@dataclass(frozen=True)
class ModelPoint:
    """The model's moments of every design at one phi, with derivatives in phi.

    Attributes:
        phi: (4,) the point.
        means: per design, (3,) mean of v.
        covs: per design, (3, 3) model covariance of v.
        d_means: per design, (4, 3) d mean / d phi (None when not computed).
        d_covs: per design, (4, 3, 3) d cov / d phi (None when not computed).
        anchor: the phi where the derivatives were evaluated (``phi`` unless
            they were carried over from a nearby point by :func:`with_moments`).
    """

    phi: FloatArray
    means: dict[Design, FloatArray]
    covs: dict[Design, FloatArray]
    d_means: dict[Design, FloatArray] | None
    d_covs: dict[Design, FloatArray] | None
    anchor: FloatArray


def with_moments(point: ModelPoint, moved: ModelPoint) -> ModelPoint:
    """``moved``'s phi and moments with ``point``'s derivatives (and anchor)."""
    return ModelPoint(moved.phi, moved.means, moved.covs, point.d_means, point.d_covs, point.anchor)


@lru_cache(maxsize=64)
def design_path(design: Design) -> EncoderPath:
    """The design's encoder path (immutable; building it costs as much as the moments)."""
    return design.path()


def model_point(phi: FloatArray, designs: Iterable[Design], derivatives: bool) -> ModelPoint:
    """Evaluate the moments (and, if asked, their phi-derivatives) of each design."""
    params = from_phi(phi)
    scale = np.array([1.0, 1.0, params.k_theta, params.k_rho])
    means: dict[Design, FloatArray] = {}
    covs: dict[Design, FloatArray] = {}
    d_means: dict[Design, FloatArray] = {}
    d_covs: dict[Design, FloatArray] = {}
    for design in designs:
        if derivatives:
            d = moment_derivatives(design_path(design), params)
            means[design], covs[design] = d.mean, d.cov
            d_means[design] = d.d_mean * scale[:, None]
            d_covs[design] = d.d_cov * scale[:, None, None]
        else:
            m = pose_moments(design_path(design), params)
            means[design], covs[design] = m.mean, m.cov
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
        gradient: (4,) d NLL / d phi, or None.
        information: (4, 4) expected Fisher information in phi, or None.
    """

    nll: float
    gradient: FloatArray | None
    information: FloatArray | None


def _stack(groups: Sequence[TrialGroup], point: ModelPoint) -> tuple[FloatArray, ...]:
    n = np.array([g.weight for g in groups], dtype=np.float64)
    s = np.array([g.total for g in groups])
    t = np.array([g.outer for g in groups])
    mu = np.array([align_heading(point.means[g.design], g.reference) for g in groups])
    cov = np.array([point.covs[g.design] + g.measurement_cov for g in groups])
    return n, s, t, mu, cov


def evaluate(
    groups: Sequence[TrialGroup], point: ModelPoint, cox_reid: bool = False
) -> LikelihoodValue:
    """NLL of the grouped trials at ``point``; score and information too when
    ``point`` carries derivatives. ``cox_reid``: the adjusted NLL (see the
    module docstring; needs derivatives, else the plain NLL is returned)."""
    groups = [g for g in groups if g.n > 0]
    n, s, t, mu, cov = _stack(groups, point)
    counts = np.array([g.n for g in groups], dtype=np.float64)
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
    if point.d_means is None or point.d_covs is None:
        return LikelihoodValue(nll, None, None)
    d_mu = np.array([point.d_means[g.design] for g in groups])  # (G, 4, 3)
    d_cov = np.array([point.d_covs[g.design] for g in groups])  # (G, 4, 3, 3)
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
        adjustment = _cox_reid(mean_info[:2, :2], n, d_mu, np.asarray(inv, np.float64), w)
        if adjustment is not None:
            nll += adjustment[0]
            grad = grad + adjustment[1]
    return LikelihoodValue(nll, grad, 0.5 * (info + info.T))


def _cox_reid(
    info_bb: FloatArray, n: FloatArray, d_mu: FloatArray, inv: FloatArray, w: FloatArray
) -> tuple[float, FloatArray] | None:
    """(1/2 log det I_bb, its gradient in phi), or None when I_bb is singular."""
    sign, logdet = np.linalg.slogdet(info_bb)
    if sign <= 0 or not math.isfinite(logdet):
        return None
    inv_bb = np.linalg.inv(info_bb)
    # d I_bb / d phi_a = -sum W dmu_b^T S^-1 dS_a S^-1 dmu_c, for a = log K_theta, log K_rho
    d_info = -np.einsum("g,gbi,gaij,gjk,gck->abc", n, d_mu[:, :2], w, inv, d_mu[:, :2])
    grad = np.zeros(4)
    grad[2:] = 0.5 * np.einsum("bc,acb->a", inv_bb, d_info[2:])
    return 0.5 * float(logdet), grad
