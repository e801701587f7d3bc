"""Odometry pose covariance for any path, and a per-metre model for an EKF.

This is the number a user calibrates for: given estimated parameters, how far
off is odometry after a path? Two ways:

- closed form: :func:`predicted_moments` is the model's exact mean and
  covariance of the pose change (x m, y m, Delta rad) of one run
  (:func:`odohil.science.moments.pose_moments`);
- simulation: :func:`simulated_moments` runs the discrete model and reports
  the sample mean and covariance with their Monte Carlo standard errors.

EKF model (:func:`ekf_increment`): for a straight encoder step of signed
length d at real heading theta, to leading order in |d| for each entry, with
g = 1 + E_T and a = |d|,

    mean:   dtheta = E_R d,  (dx, dy) = g d (cos phi, sin phi),  phi = theta + E_R d / 2
    Q_local (along-track u, cross-track v, heading h):
        Var u = K_rho a,  Var v = g^2 K_theta a^3 / 3,  Var h = K_theta a,
        Cov(v, h) = sign(d) g K_theta a^2 / 2,  Cov(u, .) = 0
    Q = T Q_local T^T,  T = [[cos phi, -sin phi, 0], [sin phi, cos phi, 0], [0, 0, 1]]

and the state Jacobian F = [[1, 0, -dy], [0, 1, dx], [0, 0, 1]]. Dropping the
a^3 and a^2 terms gives the familiar diag(K_rho, 0, K_theta) |d| per metre;
keeping them makes :func:`ekf_moments` converge to the exact covariance as
the step shrinks (up to the heading-noise nonlinearity, relative error of
order K_theta times the distance).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from odohil.errors import ParameterError
from odohil.science.moments import PoseMoments, pose_moments
from odohil.science.parameters import ErrorParameters
from odohil.science.paths import EncoderPath, FloatArray
from odohil.science.simulator import DEFAULT_SEGMENT_M, SeedLike, simulate

DEFAULT_EKF_STEP_M = 0.05


@dataclass(frozen=True)
class SimulatedMoments:
    """Sample moments of simulated pose changes (x m, y m, Delta rad).

    Attributes:
        mean: (3,) sample mean.
        cov: (3, 3) sample covariance (ddof 1).
        mean_se: (3,) Monte Carlo standard errors of ``mean``.
        cov_se: (3, 3) Monte Carlo standard errors of ``cov`` (from fourth moments).
        n_trials: number of simulated trials.
    """

    mean: FloatArray
    cov: FloatArray
    mean_se: FloatArray
    cov_se: FloatArray
    n_trials: int


def predicted_moments(path: EncoderPath, params: ErrorParameters) -> PoseMoments:
    """Exact mean and covariance of one run's pose change (closed form), SI."""
    return pose_moments(path, params)


def sample_moments(poses: FloatArray) -> SimulatedMoments:
    """Mean, covariance and their standard errors of pose changes (n, 3), n >= 2."""
    n = poses.shape[0]
    if poses.ndim != 2 or poses.shape[1] != 3 or n < 2:
        raise ParameterError(f"need at least 2 pose changes of shape (n, 3), got {poses.shape}")
    mean = poses.mean(axis=0)
    centred = poses - mean
    cov = centred.T @ centred / (n - 1)
    products = centred[:, :, None] * centred[:, None, :]
    cov_se = products.std(axis=0, ddof=1) / math.sqrt(n)
    mean_se = np.sqrt(np.diag(cov) / n)
    return SimulatedMoments(mean=mean, cov=cov, mean_se=mean_se, cov_se=cov_se, n_trials=n)


def simulated_moments(
    path: EncoderPath,
    params: ErrorParameters,
    n_trials: int,
    *,
    seed: SeedLike = None,
    segment_m: float = DEFAULT_SEGMENT_M,
) -> SimulatedMoments:
    """Simulate ``n_trials`` runs of ``path`` (discrete model, segments of at most
    ``segment_m`` metres) and return their sample moments."""
    if n_trials < 2:
        raise ParameterError(f"simulation needs at least 2 trials, got {n_trials}")
    result = simulate(path, params, n_trials, seed=seed, segment_m=segment_m)
    return sample_moments(result.pose_change)


def ekf_increment(
    params: ErrorParameters, step_m: float, heading_rad: float
) -> tuple[FloatArray, FloatArray]:
    """Mean pose increment (3,) and process noise Q (3, 3) of one straight encoder
    step of signed length ``step_m`` (metres) at real heading ``heading_rad``,
    world frame (m, m, rad); see the module docs for the formula."""
    if not math.isfinite(step_m) or not math.isfinite(heading_rad):
        raise ParameterError("step and heading must be finite")
    gain = 1.0 + params.e_t
    a = abs(step_m)
    sign = 1.0 if step_m >= 0 else -1.0
    mid = heading_rad + 0.5 * params.e_r * step_m
    mean = np.array(
        [gain * step_m * math.cos(mid), gain * step_m * math.sin(mid), params.e_r * step_m]
    )
    k = params.k_theta
    local = np.array(
        [
            [params.k_rho * a, 0.0, 0.0],
            [0.0, gain**2 * k * a**3 / 3.0, sign * gain * k * a**2 / 2.0],
            [0.0, sign * gain * k * a**2 / 2.0, k * a],
        ]
    )
    c, s = math.cos(mid), math.sin(mid)
    rotate = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    q: FloatArray = rotate @ local @ rotate.T
    return mean, q


def ekf_moments(
    path: EncoderPath, params: ErrorParameters, step_m: float = DEFAULT_EKF_STEP_M
) -> PoseMoments:
    """Propagate the EKF model of :func:`ekf_increment` along ``path`` in steps of
    at most ``step_m`` metres: the linearised mean and covariance of the pose
    change (Delta minus the path's winding), SI."""
    if not math.isfinite(step_m) or step_m <= 0:
        raise ParameterError(f"step_m must be a positive length, got {step_m!r}")
    legs = path.legs
    pose = np.zeros(3)
    cov = np.zeros((3, 3))
    previous_heading = 0.0
    for heading, sign, length in zip(legs.heading_rad, legs.sign, legs.length_m, strict=True):
        pose[2] += heading - previous_heading
        previous_heading = heading
        n_steps = max(1, math.ceil(length / step_m - 1e-9))
        step = float(sign * length / n_steps)
        for _ in range(n_steps):
            increment, q = ekf_increment(params, step, float(pose[2]))
            jacobian = np.array([[1.0, 0.0, -increment[1]], [0.0, 1.0, increment[0]], [0, 0, 1]])
            cov = jacobian @ cov @ jacobian.T + q
            pose = pose + increment
    pose[2] += path.net_turn_rad - previous_heading - path.winding_rad
    return PoseMoments(mean=pose, cov=0.5 * (cov + cov.T))
