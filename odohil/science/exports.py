"""What a fusion stack's configuration takes, from an estimate: formulas, no I/O.

The model (eqs. 1-4, docs/science.md): a straight encoder step of length a
metres adds Var(along-track) = K_rho a, Var(heading) = K_theta a and, from the
heading noise acting during the step, Var(cross-track) = g^2 K_theta a^3 / 3
and Cov(cross-track, heading) = g K_theta a^2 / 2 (g = 1 + E_T;
:func:`odohil.science.covariance.ekf_increment`). In-place turns are exact.
Each consumer wants these numbers in its own shape, at its own linearisation
(:class:`Linearisation`): docs/exports.md gives every formula with a worked
example.

Two rules:

- no zero where a filter needs a positive variance: every variance the model
  gives below :data:`VARIANCE_FLOOR` is written as the floor, and the entry
  is named in ``floored``;
- what odometry does not observe (z, roll, pitch and their rates) is written
  as :data:`UNOBSERVED_VARIANCE`, "odometry says nothing about this".
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from odohil.errors import ParameterError
from odohil.science.covariance import ekf_increment
from odohil.science.estimators.result import EstimateResult
from odohil.science.parameters import PARAMETER_NAMES, ErrorParameters
from odohil.science.paths import FloatArray
from odohil.science.planner import DEFAULT_SPEED_M_PER_S

VARIANCE_FLOOR = 1e-9
"""Smallest variance written (SI: m^2, rad^2, (m/s)^2, (rad/s)^2, and AMCL's
alphas). Strictly positive so that the filter's covariance stays positive
definite (a Cholesky factor exists, S = H P H^T + R inverts), and far below
anything a calibration resolves: 1e-9 m^2 is (0.03 mm)^2, 1e-9 rad^2 is
(0.002 deg)^2."""
UNOBSERVED_VARIANCE = 1e6
"""Variance written for what planar odometry does not observe (z, roll,
pitch, their rates): large enough that a filter gives it no weight."""
DEFAULT_RATE_HZ = 50.0
"""Odometry publication rate, Hz: diff_drive_controller's default ``publish_rate``."""
DEFAULT_UPDATE_MIN_D_M = 0.25
"""AMCL's update distance, m: Nav2's default ``update_min_d``."""
DEFAULT_UPDATE_MIN_A_RAD = 0.2
"""AMCL's update angle, rad: Nav2's default ``update_min_a``."""

ROBOT_LOCALIZATION_TEMPLATE: tuple[float, ...] = (
    0.05, 0.05, 0.06, 0.03, 0.03, 0.06, 0.025, 0.025, 0.04, 0.01, 0.01, 0.02, 0.01, 0.01, 0.015,
)  # fmt: skip
"""The diagonal of robot_localization's template ``process_noise_covariance``
(its params/ekf.yaml): kept for the states odometry does not inform."""
ROBOT_LOCALIZATION_STATES: tuple[str, ...] = (
    "x", "y", "z", "roll", "pitch", "yaw", "vx", "vy", "vz",
    "vroll", "vpitch", "vyaw", "ax", "ay", "az",
)  # fmt: skip


@dataclass(frozen=True)
class Linearisation:
    """Where the per-metre model is turned into a consumer's constants.

    Attributes:
        speed_m_per_s: driving speed, m/s (default: the driver's default
            translation speed, as the planner's time model).
        rate_hz: odometry publication rate, Hz (one step = speed / rate metres).
        update_min_d_m: AMCL's update distance, m.
        update_min_a_rad: AMCL's update angle, rad.
    """

    speed_m_per_s: float = DEFAULT_SPEED_M_PER_S
    rate_hz: float = DEFAULT_RATE_HZ
    update_min_d_m: float = DEFAULT_UPDATE_MIN_D_M
    update_min_a_rad: float = DEFAULT_UPDATE_MIN_A_RAD

    def __post_init__(self) -> None:
        for name in ("speed_m_per_s", "rate_hz", "update_min_d_m", "update_min_a_rad"):
            value = getattr(self, name)
            if not math.isfinite(value) or value <= 0:
                raise ParameterError(f"{name} must be a positive number, got {value!r}")

    @property
    def period_s(self) -> float:
        """One publication period, s."""
        return 1.0 / self.rate_hz

    @property
    def step_m(self) -> float:
        """Metres driven in one publication period."""
        return self.speed_m_per_s / self.rate_hz


@dataclass(frozen=True)
class Floored:
    """Values with the names of the entries raised to :data:`VARIANCE_FLOOR`."""

    values: tuple[float, ...]
    floored: tuple[str, ...] = field(default=())


def _floor(values: Sequence[float], names: Sequence[str]) -> Floored:
    out, low = [], []
    for value, name in zip(values, names, strict=True):
        if value < VARIANCE_FLOOR:
            out.append(VARIANCE_FLOOR)
            low.append(name)
        else:
            out.append(float(value))
    return Floored(tuple(out), tuple(low))


def step_covariance(params: ErrorParameters, step_m: float) -> FloatArray:
    """Covariance (3, 3) of one straight step of ``step_m`` metres in the
    step's own frame (along-track m, cross-track m, heading rad)."""
    if not math.isfinite(step_m) or step_m <= 0:
        raise ParameterError(f"the step must be a positive length, got {step_m!r} m")
    # ekf_increment rotates its local covariance to the mid-step heading
    # theta + E_R d / 2: start at -E_R d / 2 to get the step's own frame.
    _, q = ekf_increment(params, step_m, -0.5 * params.e_r * step_m)
    return q


@dataclass(frozen=True)
class OdometryCovariance:
    """nav_msgs/Odometry ``pose.covariance`` of one step (row-major 6x6 over
    x, y, z, roll, pitch, yaw; the step's own frame).

    Attributes:
        covariance: 36 numbers.
        step_m: the step, metres.
        floored: entries raised to the floor (e.g. ``y`` for a short step).
    """

    covariance: tuple[float, ...]
    step_m: float
    floored: tuple[str, ...]


def odometry_covariance(params: ErrorParameters, step_m: float) -> OdometryCovariance:
    """The 36-element pose covariance of a step of ``step_m`` metres."""
    q = step_covariance(params, step_m)
    diag = _floor([q[0, 0], q[1, 1], q[2, 2]], ("x", "y", "yaw"))
    matrix = np.diag([diag.values[0], diag.values[1], *[UNOBSERVED_VARIANCE] * 3, diag.values[2]])
    matrix[1, 5] = matrix[5, 1] = q[1, 2]
    return OdometryCovariance(tuple(float(v) for v in matrix.ravel()), step_m, diag.floored)


@dataclass(frozen=True)
class DiffDriveCovariance:
    """diff_drive_controller's ``pose_covariance_diagonal`` (x, y, z, roll,
    pitch, yaw: one publication step) and ``twist_covariance_diagonal``
    (vx, vy, vz, wx, wy, wz: velocities averaged over one period)."""

    pose_covariance_diagonal: tuple[float, ...]
    twist_covariance_diagonal: tuple[float, ...]
    linearisation: Linearisation
    floored: tuple[str, ...]


def diff_drive_covariance(params: ErrorParameters, lin: Linearisation) -> DiffDriveCovariance:
    """Both diagonals at ``lin``'s speed and rate: a step a = v T; the pose
    diagonal is the step's variances, the twist diagonal the same divided by
    T^2 (a velocity is a step over T)."""
    q = step_covariance(params, lin.step_m)
    t2 = lin.period_s**2
    pose = _floor([q[0, 0], q[1, 1], q[2, 2]], ("pose x", "pose y", "pose yaw"))
    twist = _floor([q[0, 0] / t2, q[1, 1] / t2, q[2, 2] / t2], ("twist vx", "twist vy", "twist wz"))
    u = UNOBSERVED_VARIANCE
    px, py, pyaw = pose.values
    vx, vy, wz = twist.values
    return DiffDriveCovariance(
        (px, py, u, u, u, pyaw), (vx, vy, u, u, u, wz), lin, pose.floored + twist.floored
    )


@dataclass(frozen=True)
class ProcessNoise:
    """robot_localization's ``process_noise_covariance``: 15x15 row-major
    (225 numbers), per second, diagonal.

    Attributes:
        matrix: 225 numbers.
        speed_m_per_s: the speed it is linearised at.
        from_template: states whose value is robot_localization's template
            (odometry does not inform them).
        floored: entries raised to the floor.
    """

    matrix: tuple[float, ...]
    speed_m_per_s: float
    from_template: tuple[str, ...]
    floored: tuple[str, ...]


def process_noise(params: ErrorParameters, speed_m_per_s: float) -> ProcessNoise:
    """Per second at speed v: x and y K_rho v (the along-track rate on both
    axes, the state being in the world frame; cross-track error grows through
    the heading, which the filter propagates itself), yaw K_theta v; the
    other states keep robot_localization's template values."""
    if not math.isfinite(speed_m_per_s) or speed_m_per_s <= 0:
        raise ParameterError(f"the speed must be positive, got {speed_m_per_s!r} m/s")
    ours = _floor(
        [
            params.k_rho * speed_m_per_s,
            params.k_rho * speed_m_per_s,
            params.k_theta * speed_m_per_s,
        ],
        ("x", "y", "yaw"),
    )
    diagonal = list(ROBOT_LOCALIZATION_TEMPLATE)
    diagonal[0], diagonal[1], diagonal[5] = ours.values
    template = tuple(s for i, s in enumerate(ROBOT_LOCALIZATION_STATES) if i not in (0, 1, 5))
    matrix = np.diag(diagonal)
    return ProcessNoise(
        tuple(float(v) for v in matrix.ravel()), speed_m_per_s, template, ours.floored
    )


@dataclass(frozen=True)
class AmclAlphas:
    """Nav2 AMCL's odometry model (``nav2_amcl::DifferentialMotionModel``).

    Nav2's meanings: alpha1 rotation noise from rotation, alpha2 rotation
    noise from translation, alpha3 translation noise from translation,
    alpha4 translation noise from rotation, alpha5 strafe noise from
    translation (the omni model only). Each is a variance per squared motion
    of one update (rad^2/rad^2, rad^2/m^2, m^2/m^2, m^2/rad^2, m^2/m^2).
    """

    alpha1: float
    alpha2: float
    alpha3: float
    alpha4: float
    alpha5: float
    update_min_d_m: float
    update_min_a_rad: float
    floored: tuple[str, ...]


def amcl_alphas(params: ErrorParameters, lin: Linearisation) -> AmclAlphas:
    """The alphas at AMCL's update distance d (Nav2's sampler: translation
    variance alpha3 d^2 + alpha4 (rot1^2 + rot2^2), each rotation's
    alpha1 rot^2 + alpha2 d^2):

    - alpha3 = K_rho / d: translation variance K_rho d;
    - alpha2 = K_theta / (2 d): the two rotations of a straight update add up
      to the heading variance K_theta d (the cross-track variance this
      implies, K_theta d^3 / 2, is 3/2 of the model's);
    - alpha5 = (1 + E_T)^2 K_theta / (3 d): the model's cross-track variance
      per squared step (used by the omni model only);
    - alpha1, alpha4: the model's in-place turns are exact, so the floor
      (tune them if the robot turns on its wheels).

    The update angle enters no alpha (turns carry no error in the model); it
    is stated so that the file holds AMCL's whole linearisation.
    """
    d = lin.update_min_d_m
    g = 1.0 + params.e_t
    raw = [0.0, params.k_theta / (2.0 * d), params.k_rho / d, 0.0, g**2 * params.k_theta / (3 * d)]
    alphas = _floor(raw, ("alpha1", "alpha2", "alpha3", "alpha4", "alpha5"))
    a1, a2, a3, a4, a5 = alphas.values
    return AmclAlphas(a1, a2, a3, a4, a5, d, lin.update_min_a_rad, alphas.floored)


@dataclass(frozen=True)
class Corrections:
    """The systematic part, applied in the odometry itself.

    Attributes:
        distance_scale: 1 + E_T: multiply encoder distances by it.
        distance_scale_stderr: its standard error (that of E_T).
        heading_drift_rad_per_m: E_R: add it to the heading per signed metre
            of encoder distance.
        heading_drift_stderr: its standard error, rad/m.
    """

    distance_scale: float
    distance_scale_stderr: float
    heading_drift_rad_per_m: float
    heading_drift_stderr: float


def corrections(result: EstimateResult) -> Corrections:
    """The corrections of an estimate, with their standard errors."""
    p = result.params
    return Corrections(
        1.0 + p.e_t,
        result.parameter("E_T").stderr,
        p.e_r,
        result.parameter("E_R").stderr,
    )


def parameter_covariance(result: EstimateResult) -> tuple[tuple[float, ...], ...]:
    """The covariance of the estimate's parameters, SI, in the order of
    ``result.parameters`` (E_R, E_T, K_theta, K_rho, then the turn errors
    e_turn... and K_spin of a general-path fit with turns_exact = false)."""
    matrix = np.asarray(result.covariance, dtype=np.float64)
    n = len(result.parameters)
    if matrix.shape != (n, n) or n < len(PARAMETER_NAMES):
        raise ParameterError(
            f"the estimate's covariance has shape {matrix.shape}, not ({n}, {n}) for its "
            f"{n} parameters"
        )
    return tuple(tuple(float(v) for v in row) for row in matrix)


def turn_errors(result: EstimateResult) -> tuple[tuple[str, float, float], ...]:
    """(name, value, stderr) of the turn errors a general-path fit carries
    (e_turn... as a fraction of the angle turned, K_spin rad^2/rad); empty for
    a four-parameter fit."""
    return tuple(
        (p.name, p.value, p.stderr)
        for p in result.parameters
        if p.name.startswith("e_turn") or p.name == "K_spin"
    )
