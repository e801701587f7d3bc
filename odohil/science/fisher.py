"""Fisher information and Cramer-Rao bounds of calibration experiments.

Model: each trial of a design yields a measured pose change
y = (dx m, dy m, dtheta rad), Gaussian with the model's exact mean mu(theta)
and covariance Sigma(theta) (:func:`odohil.science.moments.pose_moments`) plus
the measurement covariance C of the pose recovered from floor marks:

    y ~ N(mu(theta), S(theta)),   S = Sigma(theta) + C

with theta = (E_R rad/m, E_T, K_theta rad^2/m, K_rho m). One trial carries

    I_ab = dmu_a^T S^-1 dmu_b + 1/2 tr(S^-1 dS_a S^-1 dS_b)

and n independent trials n times that. The derivatives are fourth-order
finite differences of the exact moments (second order, step 1e-4 of the
parameter's magnitude: relative error about 1e-8).

The floor-mark measurement covariance depends on the trial's own pose change
(the distances' gradients turn with it; near the identity they turn a lot),
so for a robot description the information of a design is averaged over the
model's spread of pose changes: C is evaluated at ``n_samples`` poses drawn
from N(mu, Sigma) with a fixed seed, the per-trial information computed with
each, and averaged. Evaluating C at the mean pose only would understate the
measurement error of designs that end near their start (design B).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from odohil.errors import ParameterError
from odohil.science.floor_marks import mark_jacobian
from odohil.science.moments import BATCH_COLUMNS, PathSet, batch_moments, pose_moments
from odohil.science.parameters import PARAMETER_NAMES, ErrorParameters
from odohil.science.paths import Design, EncoderPath, FloatArray
from odohil.science.robot_description import RobotDescription, Screw

MeasurementModel = FloatArray | Callable[[Design], FloatArray] | None
"""The measurement covariance of a trial's pose change, (m^2, m rad, rad^2):
None (exact poses), one (3, 3) matrix for every design, or a callable
design -> (3, 3) or a stack (n, 3, 3) over which the information is averaged."""

PARAMETER_SCALES: tuple[float, float, float, float] = (1e-3, 1e-2, 1e-6, 1e-5)
"""Typical magnitudes (SI) of E_R, E_T, K_theta, K_rho; finite-difference steps
are a small fraction of max(|value|, scale)."""
_RELATIVE_STEP = 1e-4
_CENTRAL = ((-1.0, -0.5), (1.0, 0.5))
_FORWARD = ((0.0, -1.5), (1.0, 2.0), (2.0, -0.5))
DEFAULT_POSE_SAMPLES = 512
_MAX_CONDITION = 1e12

DEFAULT_SCREW_RADIUS_M = 0.2
"""Screws of the default layout sit on a circle of this radius, metres."""


@dataclass(frozen=True)
class MomentDerivatives:
    """The exact moments of one trial and their derivatives in the parameters.

    Attributes:
        mean: (3,) mean pose change (m, m, rad).
        cov: (3, 3) model covariance of the pose change.
        d_mean: (4, 3): d mean / d theta_a, in the order E_R, E_T, K_theta, K_rho.
        d_cov: (4, 3, 3): d cov / d theta_a.
    """

    mean: FloatArray
    cov: FloatArray
    d_mean: FloatArray
    d_cov: FloatArray


def moment_derivatives(path: EncoderPath, params: ErrorParameters) -> MomentDerivatives:
    """Mean, covariance and their parameter derivatives for one trial of ``path``.

    Central second-order differences; for K_theta or K_rho closer to zero than
    one step, one-sided second-order differences (the model is not defined
    for negative variance rates).
    """
    return many_moment_derivatives(PathSet.of((path,)), params)[0]


def many_moment_derivatives(
    paths: PathSet, params: ErrorParameters
) -> tuple[MomentDerivatives, ...]:
    """:func:`moment_derivatives` of every path of ``paths``: every path at
    every finite-difference point in one :func:`batch_moments` call (exact
    turns)."""
    values = np.array(params.as_tuple())
    rows = [values]
    plan: list[tuple[int, float, tuple[tuple[int, float], ...]]] = []  # (a, step, (row, weight))
    for a in range(4):
        step = _RELATIVE_STEP * max(abs(values[a]), PARAMETER_SCALES[a])
        one_sided = a >= 2 and values[a] - step < 0.0
        terms: list[tuple[int, float]] = []
        for offset, weight in _FORWARD if one_sided else _CENTRAL:
            if offset == 0.0:
                terms.append((0, weight))
                continue
            shifted = values.copy()
            shifted[a] += offset * step
            terms.append((len(rows), weight))
            rows.append(shifted)
        plan.append((a, step, tuple(terms)))
    table = np.zeros((len(rows), len(BATCH_COLUMNS)))
    table[:, :4] = rows
    means, covs = batch_moments(paths, table)  # (Q, T, 3), (Q, T, 3, 3)
    d_mean = np.zeros((len(paths.paths), 4, 3))
    d_cov = np.zeros((len(paths.paths), 4, 3, 3))
    for a, step, stencil in plan:
        for row, weight in stencil:
            d_mean[:, a] += weight * means[row]
            d_cov[:, a] += weight * covs[row]
        d_mean[:, a] /= step
        d_cov[:, a] /= step
    return tuple(
        MomentDerivatives(mean=means[0, i], cov=covs[0, i], d_mean=d_mean[i], d_cov=d_cov[i])
        for i in range(len(paths.paths))
    )


def trial_information(derivatives: MomentDerivatives, measurement_cov: FloatArray) -> FloatArray:
    """Fisher information (p, p) of one trial, SI (p = 4 from
    :func:`moment_derivatives`; any number of parameters whose derivatives
    the value holds, e.g. the turn errors of odohil/science/path_plans.py).

    Args:
        derivatives: from :func:`moment_derivatives` (or any d_mean (p, 3)
            and d_cov (p, 3, 3)).
        measurement_cov: (3, 3), or a stack (n, 3, 3) to average the
            information over (each trial with its own measurement covariance).

    Raises:
        ParameterError: the total covariance is singular (e.g. K_theta = 0
            with exact measurements) or the measurement covariance is malformed.
    """
    stack = np.asarray(measurement_cov, dtype=np.float64)
    if stack.shape == (3, 3):
        stack = stack[None]
    if stack.ndim != 3 or stack.shape[1:] != (3, 3) or not np.all(np.isfinite(stack)):
        raise ParameterError(
            f"measurement covariance must be a finite (3, 3) or (n, 3, 3) array, got shape "
            f"{stack.shape}"
        )
    total = derivatives.cov[None] + stack
    total = 0.5 * (total + np.swapaxes(total, 1, 2))
    eigen = np.linalg.eigvalsh(total)
    if np.any(eigen[:, 0] <= eigen[:, -1] / _MAX_CONDITION):
        raise ParameterError(
            "the pose covariance (model plus measurement) is singular: with exact "
            "measurements K_theta and K_rho must be positive"
        )
    inverse = np.linalg.inv(total)  # (n, 3, 3)
    dmu = derivatives.d_mean
    mean_part = (dmu @ inverse.mean(axis=0) @ dmu.T)[None]
    w = inverse[:, None] @ derivatives.d_cov[None]  # S^-1 dS_a, (n, 4, 3, 3)
    n, p = w.shape[:2]
    # tr(W_a W_b) = sum_ik W_a[i, k] W_b[k, i]
    flat = w.reshape(n, p, 9)
    flat_t = np.swapaxes(w, 2, 3).reshape(n, p, 9)
    cov_part = 0.5 * (flat @ np.swapaxes(flat_t, 1, 2))
    info: FloatArray = mean_part[0] + cov_part.mean(axis=0)
    return 0.5 * (info + info.T)


def fisher_information(
    designs: Sequence[tuple[Design, int]],
    params: ErrorParameters,
    measurement_cov: MeasurementModel = None,
) -> FloatArray:
    """Fisher information (4, 4) of a plan, SI, order E_R, E_T, K_theta, K_rho.

    Args:
        designs: (design, number of trials) pairs.
        params: the parameter values at which the information is evaluated.
        measurement_cov: see :data:`MeasurementModel`.
    """
    if not designs:
        raise ParameterError("a plan needs at least one design")
    info = np.zeros((4, 4))
    for design, n_trials in designs:
        if n_trials < 0:
            raise ParameterError(f"number of trials must be non-negative, got {n_trials}")
        if n_trials == 0:
            continue
        derivatives = moment_derivatives(design.path(), params)
        info += n_trials * trial_information(derivatives, _measurement_for(design, measurement_cov))
    return info


def cramer_rao(
    designs: Sequence[tuple[Design, int]],
    params: ErrorParameters,
    measurement_cov: MeasurementModel = None,
) -> FloatArray:
    """Cramer-Rao standard errors (4,) of E_R (rad/m), E_T, K_theta (rad^2/m), K_rho (m).

    Raises:
        ParameterError: the plan does not identify some parameter.
    """
    return standard_errors(fisher_information(designs, params, measurement_cov))


def standard_errors(information: FloatArray) -> FloatArray:
    """sqrt(diag(I^-1)) of a (4, 4) Fisher information, SI.

    Raises:
        ParameterError: the information is singular (a parameter is not identified).
    """
    scale = np.array(PARAMETER_SCALES)
    scaled = information * np.outer(scale, scale)
    eigen = np.linalg.eigvalsh(scaled)
    if eigen[0] <= eigen[-1] * 1e-14:
        weakest = int(np.argmax(np.abs(np.linalg.eigh(scaled)[1][:, 0])))
        raise ParameterError(
            f"the plan does not identify {PARAMETER_NAMES[weakest]}: its Fisher information "
            "is singular"
        )
    covariance = np.linalg.inv(scaled) * np.outer(scale, scale)
    errors: FloatArray = np.sqrt(np.diag(covariance))
    return errors


def _measurement_for(design: Design, model: MeasurementModel) -> FloatArray:
    if model is None:
        return np.zeros((3, 3))
    if callable(model):
        return np.asarray(model(design), dtype=np.float64)
    return np.asarray(model, dtype=np.float64)


# --- floor-mark measurement covariance ---------------------------------------


def default_description(sigma_m: float) -> RobotDescription:
    """The layout assumed when only the tape sigma (metres) is known: three screws
    on a circle of radius :data:`DEFAULT_SCREW_RADIUS_M` at 0, 120 and 240 degrees
    from the forward axis (A forward), and one cross distance, start of A to end of B."""
    r = DEFAULT_SCREW_RADIUS_M
    screws = tuple(
        Screw(name, r * math.cos(math.radians(angle)), r * math.sin(math.radians(angle)))
        for name, angle in (("A", 0.0), ("B", 120.0), ("C", 240.0))
    )
    return RobotDescription(screws=screws, sigma_m=sigma_m, cross_pairs=(("A", "B"),))


def measurement_covariance(description: RobotDescription, pose_change: FloatArray) -> FloatArray:
    """Linearised covariance of the pose recovered from floor marks, sigma^2 (J^T J)^-1.

    Args:
        description: screws, cross pairs and tape sigma (metres).
        pose_change: (3,) or (n, 3): true pose change(s) (m, m, rad).

    Returns:
        (3, 3) or (n, 3, 3) in m^2, m rad, rad^2. Where the distances do not
        pin the pose, the unpinned direction gets a very large (finite) variance.
    """
    poses = np.asarray(pose_change, dtype=np.float64)
    single = poses.ndim == 1
    poses = np.atleast_2d(poses)
    if poses.shape[1] != 3 or not np.all(np.isfinite(poses)):
        raise ParameterError(f"pose_change must be finite (3,) or (n, 3), got {poses.shape}")
    jac = mark_jacobian(description, poses)
    normal = np.einsum("nki,nkj->nij", jac, jac)
    ridge = np.einsum("nii->n", normal)[:, None, None] / _MAX_CONDITION * np.eye(3)
    cov = description.sigma_m**2 * np.linalg.inv(normal + ridge)
    cov = 0.5 * (cov + np.swapaxes(cov, 1, 2))
    result: FloatArray = cov[0] if single else cov
    return result


def pose_spread_measurement(
    description: RobotDescription,
    params: ErrorParameters,
    n_samples: int = DEFAULT_POSE_SAMPLES,
    seed: int = 0,
) -> Callable[[Design], FloatArray]:
    """A measurement model for :func:`fisher_information`: for each design, the
    floor-mark covariances (n_samples, 3, 3) at pose changes drawn from the
    model's N(mean, cov) under ``params`` (the same standard normals for every
    design, so comparisons between designs are not blurred by sampling noise)."""
    if n_samples < 1:
        raise ParameterError(f"n_samples must be at least 1, got {n_samples}")
    normals = np.random.default_rng(seed).standard_normal((n_samples, 3))
    cache: dict[Design, FloatArray] = {}

    def model(design: Design) -> FloatArray:
        if design not in cache:
            moments = pose_moments(design.path(), params)
            root = _psd_root(moments.cov)
            poses = moments.mean + normals @ root.T
            cache[design] = measurement_covariance(description, poses)
        return cache[design]

    return model


def _psd_root(cov: FloatArray) -> FloatArray:
    values, vectors = np.linalg.eigh(0.5 * (cov + cov.T))
    root: FloatArray = vectors * np.sqrt(np.clip(values, 0.0, None))
    return root
