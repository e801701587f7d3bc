"""A differential drive's odometry errors, and how they map onto the paper's.

A differential drive (the iRobot Create 2) measures each wheel with an
encoder and computes its pose from the two wheel distances with nominal
constants: counts per revolution, wheel diameter D and wheel base b. The real
robot differs (:class:`DiffDriveErrors`):

- the true left and right wheel diameters are D (1 + e_l) and D (1 + e_r);
- the true wheel base is b (1 + e_b);
- wheel slip adds noise;
- in-place turns (spins) slip too, in proportion to the angle turned.

Straight legs (both wheels' encoders report the same signed distance s):
the true wheel travels are s (1 + e_l) and s (1 + e_r), so the robot
advances s (1 + (e_l + e_r)/2) and turns s (e_r - e_l) / (b (1 + e_b)):

    E_T = (e_l + e_r) / 2
    E_R = (e_r - e_l) / (b (1 + e_b))       rad per metre, signed like s

which is exactly the paper's systematic model (eqs. 1-2, with s signed, see
odohil/science/paths.py). Slip noise on the sum and on the difference of the
wheel travels gives K_rho (variance of the travel per metre) and K_theta
(variance of the heading per metre); independent wheels with the same
variance k_w per metre give K_rho = k_w / 2 and K_theta = 2 k_w / (b (1 + e_b))^2, so
this class takes K_theta and K_rho themselves (any correlation of the wheels'
slip fits). ``tests/science/test_diff_drive.py`` checks the mapping against a
Monte Carlo integration of the wheels.

In-place spins (encoder angle a: the wheels report -a b/2 and +a b/2): the
true heading changes by a (1 + e_turn) + N(0, K_spin |a|), with

    e_turn = (1 + (e_l + e_r)/2) / (1 + e_b) - 1,

and the centre moves by a b (e_r - e_l) / 4 along the way. The paper's model
has no such error (its turns are exact, a synchronous drive steers in place
without moving its wheels over the floor), so designs with turns fold e_turn
and K_spin into E_R and K_theta: calibrate a differential drive with the
``reverse`` variant (:data:`TURN_FREE_VARIANT`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from odohil.errors import ParameterError
from odohil.science.moments import TurnErrors
from odohil.science.parameters import ErrorParameters
from odohil.science.paths import EncoderPath, FloatArray, Leg, Turn, Variant, turn_class_index
from odohil.science.simulator import (
    DEFAULT_SEGMENT_M,
    SeedLike,
    SimulationResult,
    drive_straight,
    make_rng,
    segments_per_leg,
)

TURN_FREE_VARIANT: Variant = "reverse"
"""The design variant for robots whose in-place turns carry error."""


@dataclass(frozen=True)
class DiffDriveGeometry:
    """Nominal kinematic constants of a differential drive.

    Attributes:
        counts_per_rev: encoder counts per wheel revolution.
        wheel_diameter_m: wheel diameter, m (the left wheel's when
            ``right_wheel_diameter_m`` is given).
        wheel_base_m: distance between the wheels' contact points, m.
        right_wheel_diameter_m: the right wheel's diameter when the nominal
            constants give the two wheels apart (``wheel_diameter_m = [left,
            right]`` in a robot description), m; None: the same as the left.

    No defaults: a robot's nominal constants are its backend's
    (``RobotFacts.drive``, e.g. odohil/driver/create2/facts.py) or its
    description's.
    """

    counts_per_rev: float
    wheel_diameter_m: float
    wheel_base_m: float
    right_wheel_diameter_m: float | None = None

    def __post_init__(self) -> None:
        for name in ("counts_per_rev", "wheel_diameter_m", "wheel_base_m"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ParameterError(f"{name} must be a positive number, got {value!r}")
        right = self.right_wheel_diameter_m
        if right is not None and not (math.isfinite(right) and right > 0):
            raise ParameterError(f"right_wheel_diameter_m must be a positive number, got {right!r}")

    @property
    def wheel_diameters_m(self) -> tuple[float, float]:
        """(left, right) wheel diameters, m."""
        right = self.right_wheel_diameter_m
        return self.wheel_diameter_m, self.wheel_diameter_m if right is None else right

    @property
    def metres_per_count(self) -> float:
        """Wheel travel of one encoder count, m (the two wheels' mean)."""
        left, right = self.wheel_diameters_m
        return math.pi * 0.5 * (left + right) / self.counts_per_rev

    @property
    def wheel_metres_per_count(self) -> tuple[float, float]:
        """(left, right) wheel travel of one encoder count, m."""
        left, right = self.wheel_diameters_m
        return math.pi * left / self.counts_per_rev, math.pi * right / self.counts_per_rev

    def counts_for(self, distance_m: float) -> float:
        """Encoder counts of a wheel travel of ``distance_m`` (m)."""
        return distance_m / self.metres_per_count

    def wheel_travel(self, left_counts: int, right_counts: int) -> tuple[float, float]:
        """Left and right wheel travel (m) of encoder deltas (counts)."""
        left, right = self.wheel_metres_per_count
        return left_counts * left, right_counts * right


def odometry_step(
    pose: tuple[float, float, float], left_m: float, right_m: float, wheel_base_m: float
) -> tuple[float, float, float]:
    """Advance an odometry pose (x m, y m, theta rad) by wheel travels (m),
    along the arc they describe (exact for constant wheel speeds); theta is
    not wrapped."""
    x, y, theta = pose
    d = 0.5 * (left_m + right_m)
    d_theta = (right_m - left_m) / wheel_base_m
    if abs(d_theta) < 1e-9:
        mid = theta + 0.5 * d_theta
        return x + d * math.cos(mid), y + d * math.sin(mid), theta + d_theta
    radius = d / d_theta
    return (
        x + radius * (math.sin(theta + d_theta) - math.sin(theta)),
        y - radius * (math.cos(theta + d_theta) - math.cos(theta)),
        theta + d_theta,
    )


@dataclass(frozen=True)
class DiffDriveErrors:
    """How a real differential drive differs from its nominal constants.

    Attributes:
        left_scale: e_l, true left wheel diameter / nominal - 1.
        right_scale: e_r, true right wheel diameter / nominal - 1.
        base_scale: e_b, true wheel base / nominal - 1.
        k_theta: heading variance per metre driven straight, rad^2/m.
        k_rho: travel variance per metre driven straight, m.
        k_spin: heading variance per radian turned in place, rad^2/rad.
        wheel_base_m: the nominal wheel base b, m: the robot's own
            (``DiffDriveGeometry.wheel_base_m``, e.g. odohil/protocol/create2/geometry.py);
            no default, a robot's constants are not the science layer's.
    """

    wheel_base_m: float
    left_scale: float = 0.0
    right_scale: float = 0.0
    base_scale: float = 0.0
    k_theta: float = 0.0
    k_rho: float = 0.0
    k_spin: float = 0.0

    def __post_init__(self) -> None:
        for name in ("left_scale", "right_scale", "base_scale"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > -1.0):
                raise ParameterError(f"{name} must be a number above -1, got {value!r}")
        for name in ("k_theta", "k_rho", "k_spin"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0.0):
                raise ParameterError(f"{name} is a variance rate, >= 0; got {value!r}")
        if not (math.isfinite(self.wheel_base_m) and self.wheel_base_m > 0):
            raise ParameterError(f"wheel_base_m must be positive, got {self.wheel_base_m!r}")

    @property
    def true_wheel_base_m(self) -> float:
        """b (1 + e_b), m."""
        return self.wheel_base_m * (1.0 + self.base_scale)

    def straight_parameters(self) -> ErrorParameters:
        """The paper's four parameters of the straight legs (module docstring)."""
        return ErrorParameters(
            e_r=(self.right_scale - self.left_scale) / self.true_wheel_base_m,
            e_t=0.5 * (self.left_scale + self.right_scale),
            k_theta=self.k_theta,
            k_rho=self.k_rho,
        )

    @property
    def turn_scale(self) -> float:
        """e_turn: an in-place turn of encoder angle a really turns a (1 + e_turn)."""
        return (1.0 + 0.5 * (self.left_scale + self.right_scale)) / (1.0 + self.base_scale) - 1.0

    @classmethod
    def from_parameters(
        cls,
        params: ErrorParameters,
        *,
        turn_scale: float = 0.0,
        k_spin: float = 0.0,
        wheel_base_m: float,
    ) -> DiffDriveErrors:
        """The wheel errors that give ``params`` on straight legs and
        ``turn_scale`` (e_turn) on spins (the inverse of the mapping above)."""
        if not (math.isfinite(turn_scale) and turn_scale > -1.0):
            raise ParameterError(f"turn_scale must be a number above -1, got {turn_scale!r}")
        base_scale = (1.0 + params.e_t) / (1.0 + turn_scale) - 1.0
        half_gap = 0.5 * params.e_r * wheel_base_m * (1.0 + base_scale)
        return cls(
            left_scale=params.e_t - half_gap,
            right_scale=params.e_t + half_gap,
            base_scale=base_scale,
            k_theta=params.k_theta,
            k_rho=params.k_rho,
            k_spin=k_spin,
            wheel_base_m=wheel_base_m,
        )


def spin(
    x: FloatArray,
    y: FloatArray,
    theta: FloatArray,
    angle_rad: float,
    errors: DiffDriveErrors,
    rng: np.random.Generator,
) -> None:
    """Turn in place by the encoder angle ``angle_rad`` (CCW +): updates the
    true poses (arrays of one shape (n,)) in place (module docstring)."""
    if angle_rad == 0.0:
        return
    true_turn = angle_rad * (1.0 + errors.turn_scale)
    if errors.k_spin > 0.0:
        noise = rng.standard_normal(theta.shape) * math.sqrt(errors.k_spin * abs(angle_rad))
    else:
        noise = np.zeros(theta.shape)
    drift = 0.25 * angle_rad * errors.wheel_base_m * (errors.right_scale - errors.left_scale)
    if drift != 0.0:
        # the chord of the arc the centre moves along, at the mean heading
        chord = drift * np.sinc((true_turn + noise) / (2.0 * math.pi))
        mid = theta + 0.5 * (true_turn + noise)
        x += chord * np.cos(mid)
        y += chord * np.sin(mid)
    theta += true_turn + noise


def simulate_diff_drive(
    path: EncoderPath,
    errors: DiffDriveErrors,
    n_trials: int,
    *,
    seed: SeedLike = None,
    segment_m: float = DEFAULT_SEGMENT_M,
) -> SimulationResult:
    """Simulate ``n_trials`` runs of ``path`` on a differential drive.

    Straight legs follow the paper's discrete model with
    :meth:`DiffDriveErrors.straight_parameters` (the same
    :func:`odohil.science.simulator.drive_straight` the fakes use); turns
    follow :func:`spin`. The pose changes are as
    :func:`odohil.science.simulator.simulate` reports them (heading change
    minus the path's winding).
    """
    if n_trials < 1:
        raise ParameterError(f"n_trials must be at least 1, got {n_trials}")
    if not math.isfinite(segment_m) or segment_m <= 0:
        raise ParameterError(f"segment_m must be a positive length, got {segment_m!r}")
    rng = make_rng(seed)
    params = errors.straight_parameters()
    x, y, theta = np.zeros(n_trials), np.zeros(n_trials), np.zeros(n_trials)
    seg: list[float] = []
    for step in path.steps:
        if isinstance(step, Turn):
            spin(x, y, theta, step.angle_rad, errors, rng)
            continue
        assert isinstance(step, Leg)
        count = segments_per_leg(abs(step.length_m), segment_m)
        seg.append(abs(step.length_m) / count)
        drive_straight(x, y, theta, step.length_m / count, count, params, rng)
    poses = np.stack([x, y, theta - path.winding_rad], axis=1)
    return SimulationResult(pose_change=poses, trajectory=None, segment_m=np.array(seg))


def simulate_turn_errors(
    path: EncoderPath,
    params: ErrorParameters,
    turns: TurnErrors,
    n_trials: int,
    *,
    seed: SeedLike = None,
    segment_m: float = DEFAULT_SEGMENT_M,
) -> SimulationResult:
    """Simulate ``n_trials`` runs of ``path`` under the turn-error model of
    :func:`odohil.science.moments.pose_moments`: legs as the paper's discrete
    model (:func:`odohil.science.simulator.drive_straight`), each turn of
    encoder angle a in class c turning a (1 + e_c), plus N(0, K_spin |a|) for
    a spin; the centre does not move during a turn (unlike :func:`spin`, whose
    wheels' diameter difference moves it). Pose changes as
    :func:`odohil.science.simulator.simulate` reports them."""
    if n_trials < 1:
        raise ParameterError(f"n_trials must be at least 1, got {n_trials}")
    if not math.isfinite(segment_m) or segment_m <= 0:
        raise ParameterError(f"segment_m must be a positive length, got {segment_m!r}")
    rng = make_rng(seed)
    scales = turns.scales
    x, y, theta = np.zeros(n_trials), np.zeros(n_trials), np.zeros(n_trials)
    seg: list[float] = []
    for step in path.steps:
        if isinstance(step, Turn):
            if step.angle_rad == 0.0:
                continue
            theta += step.angle_rad * (1.0 + scales[turn_class_index(step)])
            if step.kind == "spin" and turns.k_spin > 0.0:
                theta += rng.standard_normal(n_trials) * math.sqrt(
                    turns.k_spin * abs(step.angle_rad)
                )
            continue
        count = segments_per_leg(abs(step.length_m), segment_m)
        seg.append(abs(step.length_m) / count)
        drive_straight(x, y, theta, step.length_m / count, count, params, rng)
    poses = np.stack([x, y, theta - path.winding_rad], axis=1)
    return SimulationResult(pose_change=poses, trajectory=None, segment_m=np.array(seg))
