"""Martinelli's sequential method of moments (section 4), over any mix of designs.

From the design with the smallest k (among those whose signed distance is not
zero, so that phi1 sees E_R), in this order:

    E_R     = (phi1 - Delta_bar) / rho_signed                      (eq. 33)
    K_theta = (phi2 - <var of measured Delta>) / rho                (eq. 34)
    1 + E_T = least-squares scale of (phi3, phi4) onto the corrected
              eqs. 36-39 evaluated at E_T = 0 with the E_R, K_theta above

and from the design with the largest k:

    K_rho   = (phi5 - <var of measured x + y> - drift(E_R, K_theta, E_T)) / rho

where drift is the corrected eq. (40) without its K_rho term
(:func:`odohil.science.closed_forms.forth_and_back_means`). Subtracting the
measurement variances removes the bias they would otherwise add to phi2 and
phi5. Variance rates that come out negative are reported as 0.

Standard errors: the delta method. The estimator is a smooth function of the
sample moments m = (phi1..phi4 of the first design, phi5 of the second); the
covariance of m is that of Gaussian trials with the model's mean and
covariance at the estimate plus the mean measurement covariance (second and
fourth moments of a Gaussian, by Isserlis' theorem), and the Jacobian of the
estimator is taken by central differences.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from odohil.errors import MeasurementError
from odohil.science.closed_forms import forth_and_back_means
from odohil.science.estimators.observations import DesignSummary
from odohil.science.moments import pose_moments
from odohil.science.parameters import ErrorParameters
from odohil.science.paths import FloatArray

_MIN_GAIN = 1e-3
"""1 + E_T below this is reported as this: the model needs a positive scale."""
_MOMENT_STEPS = np.array([1e-7, 1e-9, 1e-6, 1e-6, 1e-8])
"""Central-difference steps for phi1 (rad), phi2 (rad^2), phi3, phi4 (m), phi5 (m^2)."""


@dataclass(frozen=True)
class PaperEstimate:
    """The sequential method's estimate.

    Attributes:
        params: the estimate (SI; negative variance rates reported as 0).
        covariance: (4, 4) delta-method covariance, SI, order E_R, E_T, K_theta, K_rho.
        first: the design that gave E_R, K_theta and E_T.
        second: the design that gave K_rho.
        raw_k: the variance rates before clipping at 0 (K_theta, K_rho).
    """

    params: ErrorParameters
    covariance: FloatArray
    first: DesignSummary
    second: DesignSummary
    raw_k: tuple[float, float]


def choose_designs(summaries: Sequence[DesignSummary]) -> tuple[DesignSummary, DesignSummary]:
    """(design for E_R, K_theta, E_T; design for K_rho), as in the paper.

    Raises:
        MeasurementError: no design has two trials and a non-zero signed distance.
    """
    usable = [s for s in summaries if s.n >= 2 and abs(s.design.path().signed_distance_m) > 0.0]
    if not usable:
        raise MeasurementError(
            "an estimate needs at least 2 trials of one design whose signed "
            "distance is not zero (the 'turn' variant, or an odd number of legs), "
            "so that phi1 measures E_R (every method starts from the paper's)"
        )
    first = min(usable, key=lambda s: (s.design.k, -s.n * s.design.distance_m))
    second = max(summaries, key=lambda s: (s.design.k, s.n * s.design.distance_m))
    return first, second


def _estimate_from_moments(
    m: FloatArray, first: DesignSummary, second: DesignSummary
) -> tuple[float, float, float, float]:
    """(E_R, E_T, K_theta, K_rho) from m = (phi1, phi2, phi3, phi4, phi5); K not clipped."""
    path = first.design.path()
    e_r = (m[0] - path.encoder_end_pose()[2]) / path.signed_distance_m
    k_theta = (m[1] - first.measurement_cov[2, 2]) / path.distance_m
    unit = forth_and_back_means(first.design, ErrorParameters(e_r, 0.0, max(k_theta, 0.0), 0.0))
    norm = unit.x**2 + unit.y**2
    gain = (m[2] * unit.x + m[3] * unit.y) / norm if norm > 0.0 else 1.0
    e_t = max(gain, _MIN_GAIN) - 1.0
    drift = forth_and_back_means(
        second.design, ErrorParameters(e_r, e_t, max(k_theta, 0.0), 0.0)
    ).phi5
    meas = second.measurement_cov[0, 0] + second.measurement_cov[1, 1]
    k_rho = (m[4] - meas - drift) / second.design.distance_m
    return e_r, e_t, k_theta, k_rho


def _quadratic_cov(
    b: Sequence[FloatArray], a: Sequence[FloatArray], mu: FloatArray, sigma: FloatArray
) -> FloatArray:
    """Covariance of u_j = b_j.v + v^T A_j v for v ~ N(mu, sigma) (A_j symmetric)."""
    k = len(b)
    out = np.empty((k, k))
    for i in range(k):
        for j in range(k):
            out[i, j] = (
                b[i] @ sigma @ b[j]
                + 2.0 * b[i] @ sigma @ a[j] @ mu
                + 2.0 * b[j] @ sigma @ a[i] @ mu
                + 2.0 * np.trace(a[i] @ sigma @ a[j] @ sigma)
                + 4.0 * mu @ a[i] @ sigma @ a[j] @ mu
            )
    return out


def _moment_covariance(
    params: ErrorParameters, first: DesignSummary, second: DesignSummary
) -> FloatArray:
    """Covariance (5, 5) of (phi1, phi2, phi3, phi4, phi5) for Gaussian trials."""
    e = np.eye(3)
    zero = np.zeros((3, 3))
    xy = np.diag([1.0, 1.0, 0.0])
    heading = np.outer(e[2], e[2])

    def moments(summary: DesignSummary) -> tuple[FloatArray, FloatArray]:
        m = pose_moments(summary.design.path(), params)
        return m.mean, m.cov + summary.measurement_cov

    mu1, sigma1 = moments(first)
    # phi2 as the quadratic form (v - mu)^T H (v - mu)
    b1 = [e[2], -2.0 * heading @ mu1, e[0], e[1]]
    a1 = [zero, heading, zero, zero]
    if second.design == first.design:
        cov = _quadratic_cov([*b1, np.zeros(3)], [*a1, xy], mu1, sigma1) / first.n
        cov[1, 1] *= first.n / (first.n - 1)
        return cov
    cov = np.zeros((5, 5))
    cov[:4, :4] = _quadratic_cov(b1, a1, mu1, sigma1) / first.n
    cov[1, 1] *= first.n / (first.n - 1)
    mu2, sigma2 = moments(second)
    cov[4, 4] = _quadratic_cov([np.zeros(3)], [xy], mu2, sigma2)[0, 0] / second.n
    return cov


def paper_estimate(summaries: Sequence[DesignSummary]) -> PaperEstimate:
    """The sequential method of moments on pooled design statistics.

    Raises:
        MeasurementError: see :func:`choose_designs`.
    """
    first, second = choose_designs(summaries)
    m = np.array(
        [
            first.mean[2],
            first.heading_variance,
            first.mean[0],
            first.mean[1],
            second.mean_square_distance,
        ]
    )
    e_r, e_t, k_theta, k_rho = _estimate_from_moments(m, first, second)
    params = ErrorParameters(e_r, e_t, max(k_theta, 0.0), max(k_rho, 0.0))
    jacobian = np.empty((4, 5))
    for j, step in enumerate(_MOMENT_STEPS):
        h = step * max(1.0, abs(m[j]) / step * 1e-6)
        up, down = m.copy(), m.copy()
        up[j] += h
        down[j] -= h
        jacobian[:, j] = (
            np.array(_estimate_from_moments(up, first, second))
            - np.array(_estimate_from_moments(down, first, second))
        ) / (2.0 * h)
    cov = jacobian @ _moment_covariance(params, first, second) @ jacobian.T
    if not np.all(np.isfinite(cov)):
        cov = np.full((4, 4), math.inf)
    return PaperEstimate(params, 0.5 * (cov + cov.T), first, second, (k_theta, k_rho))
