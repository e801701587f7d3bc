"""Per-trial scores, and how far the data's own spread of them exceeds the model's.

The score of trial i in phi = (E_R, E_T, log K_theta, log K_rho), with
weight w_i (1 for the Gaussian fit; the robust fit's
r_i + (1 - r_i) / INFLATION, odohil/science/estimators/robust.py):

    g_i = -w_i dmu^T S^-1 e_i + 1/2 tr(S^-1 dS (I - w_i S^-1 e_i e_i^T))

with e_i the trial's residual and S = Sigma_d + C_i. Under the model,
E[g_i g_i^T] is the trial's expected information, so the ratio of the
sandwich variance (J^-1 K J^-1)_kk, K = n / (n - 4) sum g_i g_i^T, to the
model variance (J^-1)_kk is about 1. Tape errors with heavier tails than the
Gaussian the likelihood assumes (a Student-t tape: what remains after the
robust fit has set the worst trials aside still has excess kurtosis) make the
squared residuals vary more than the model says, and the ratio of a variance
rate grows with that excess: the data are telling us that the likelihood's
curvature overstates what they know about K (Royall 1986; Chandler and Bate
2007 for profile likelihoods).
"""

from __future__ import annotations

from collections.abc import Hashable, Sequence

import numpy as np

from odohil.science.estimators.likelihood import ModelPoint, model_point
from odohil.science.estimators.observations import Observation, align_heading
from odohil.science.paths import FloatArray

ScoredTrial = tuple[Hashable, FloatArray, FloatArray]
"""(key of its moments in a model point, pose change (3,), measurement covariance (3, 3))."""


def trial_scores(
    observations: Sequence[Observation], phi: FloatArray, weights: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """(scores, information): the (n, 4) per-trial scores g_i in phi and the
    (4, 4) weighted expected information sum w_i I_i (mean part weighted,
    covariance part as in the robust M-step), both at ``phi``."""
    designs = list(dict.fromkeys(o.design for o in observations))
    point: ModelPoint = model_point(phi, designs, derivatives=True)
    rows = [(o.design, o.pose_change, o.measurement_cov) for o in observations]
    return point_scores(point, rows, weights)


def point_scores(
    point: ModelPoint, trials: Sequence[ScoredTrial], weights: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """:func:`trial_scores` of any model: (n, p) scores and (p, p) weighted
    information at ``point`` (which carries derivatives for every key)."""
    assert point.d_means is not None
    assert point.d_covs is not None
    n, size = len(trials), point.layout.size
    scores = np.zeros((n, size))
    information = np.zeros((size, size))
    for i, (key, pose, measurement_cov) in enumerate(trials):
        w_i = float(weights[i])
        mean = align_heading(point.means[key], float(pose[2]))
        cov = point.covs[key] + measurement_cov
        inv = np.linalg.inv(0.5 * (cov + cov.T))
        resid = pose - mean
        d_mu = point.d_means[key]
        w = np.einsum("ij,ajk->aik", inv, point.d_covs[key])  # S^-1 dS_a
        inv_rr = w_i * inv @ np.outer(resid, resid)
        scores[i] = -w_i * d_mu @ inv @ resid + 0.5 * (
            np.einsum("aii->a", w) - np.einsum("aij,ji->a", w, inv_rr)
        )
        information += w_i * (d_mu @ inv @ d_mu.T + 0.5 * np.einsum("aij,bji->ab", w, w))
    return scores, information


def sandwich_ratio(scores: FloatArray, information: FloatArray) -> FloatArray:
    """Per parameter, (J^-1 K J^-1)_kk / (J^-1)_kk with K = n / (n - p) sum
    g_i g_i^T (the usual small-sample correction for the p fitted
    parameters, 4 in the paper's model); inf where the information is
    singular, nan with p or fewer trials."""
    n, size = scores.shape
    if n <= size:
        return np.full(size, np.nan)
    try:
        cov = np.linalg.inv(information)
    except np.linalg.LinAlgError:
        return np.full(size, np.inf)
    spread = n / (n - float(size)) * scores.T @ scores
    sandwich = cov @ spread @ cov
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio: FloatArray = np.diag(sandwich) / np.diag(cov)
    return ratio
