"""Recorded odometry made into an encoder path of legs and turns, compressed.

A log reports the odometry at every sample (50 ms in the optiodom data, 100 Hz
on a ROS robot). The estimator wants an :class:`~odohil.science.paths.EncoderPath`:
straight legs at constant encoder heading with turns between them. Each sample
would give one leg, hundreds per circle; :func:`compress_odometry` cuts the
odometry into *segments* instead and makes each segment one leg with a turn on
either side:

- a segment ends when the encoder heading has moved more than
  :data:`HEADING_STEP_RAD` from its value at the segment's start, when it has
  driven :data:`LEG_MAX_M`, or when the motion changes kind (forwards,
  backwards, in place);
- its leg is the *chord* from the segment's first to its last odometry
  position (signed: negative when driven backwards) and its turns are the
  heading change from the segment's start heading to the chord's, then from
  the chord's to the end heading. So the compressed path ends exactly where the
  odometry ends (x, y and heading, up to rounding; tests check 1e-9 m and
  1e-12 rad), whatever the segment's shape.

The price is the distance: a chord is shorter than the arc the wheels rolled,
by a^2/24 of it for a circular arc turning a (0.375 % at a = 0.3 rad). The
error model multiplies distances by E_T (-0.25 % on the optiodom robot), so
the leg lengths' shortfall moves a predicted pose by less than 1e-5 of the
distance; it moves the variances (K_theta, K_rho times distance) by the same
0.4 % at most. A circle of two laps (4 pi rad) becomes 42 legs.

Turns carry a kind (:class:`~odohil.science.paths.Turn`): the turns of a
segment driven in place (its samples' radius of turn ``|ds / dtheta|`` below
:data:`SPIN_RADIUS_M`) are ``"spin"``, the heading changes of curves ``"arc"``.
A path needs a leg; a spin whose odometry does not move the centre at all gets
a leg of :data:`PLACEHOLDER_LEG_M` (1 nm), which changes no prediction.

:func:`integrate_ticks` turns cumulative wheel encoder counts into odometry
poses (the exact arc of each sample, as :func:`odohil.science.diff_drive.odometry_step`),
and :func:`path_family` names a path's family and direction for the model checks.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from odohil.errors import MeasurementError
from odohil.science.frames import rotate_points
from odohil.science.path_trials import Direction
from odohil.science.paths import EncoderPath, FloatArray, Leg, Step, Turn, TurnKind
from odohil.units import wrap_angle

HEADING_STEP_RAD = 0.3
"""Largest excursion of the encoder heading within one leg, rad (17 degrees):
a chord then falls short of its arc by at most 0.4 % (module docstring) and a
two-lap circle is 42 legs."""
LEG_MAX_M = 1.0
"""Longest leg, m: bounds what a slow wobble inside a segment could hide
(the chord of a wiggly segment is shorter than the distance driven)."""
SPIN_RADIUS_M = 0.02
"""A sample whose radius of turn |ds / dtheta| is below this (m) turns in
place: a spin's wheel asymmetry moves the centre by millimetres over half a
turn (radius ~2 mm on the optiodom robot), while the tightest curve a
differential drive drives on purpose has a radius of at least half its wheel
base (0.1 m for a 0.2 m base)."""
PLACEHOLDER_LEG_M = 1e-9
"""The leg of a spin whose odometry does not move the centre at all, m."""
STRAIGHT_TURN_RAD = 0.3
"""A path turning less than this in total (sum of |turns|, rad) is ``straight``."""
SPIN_DRIFT_M = 0.05
"""A path of spins driving less than this in total (m) is a ``spin``."""
MAX_SAMPLES = 10_000_000
"""Most odometry samples of one trial."""

JUDGE_M = 0.005
"""Motion either side of a sample over which its kind is judged, m."""
JUDGE_RADIUS_M = 0.1
"""Metres of motion one radian of turn counts for in :data:`JUDGE_M`."""
STRAIGHT_OTHER_WAY = 0.05
"""A straight path may drive this fraction of its distance the other way
(twitches at a start)."""

_TINY_M = 1e-12


@dataclass(frozen=True)
class CompressionBounds:
    """How :func:`compress_odometry` cuts the odometry (module docstring).

    Attributes:
        heading_step_rad: largest heading excursion within a leg, rad.
        leg_max_m: longest leg, m.
        spin_radius_m: radius of turn below which a sample turns in place, m.
    """

    heading_step_rad: float = HEADING_STEP_RAD
    leg_max_m: float = LEG_MAX_M
    spin_radius_m: float = SPIN_RADIUS_M

    def __post_init__(self) -> None:
        for name in ("heading_step_rad", "leg_max_m", "spin_radius_m"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise MeasurementError(f"{name} must be a positive number, got {value!r}")


def in_start_frame(poses: FloatArray) -> FloatArray:
    """Odometry poses (n, 3: x m, y m, theta rad) seen from the first pose,
    headings unwrapped along the samples (each step taken within pi)."""
    poses = np.asarray(poses, dtype=np.float64)
    if poses.ndim != 2 or poses.shape[1] != 3 or len(poses) < 1:
        raise MeasurementError(f"odometry poses must be an (n, 3) array, got {poses.shape}")
    if len(poses) > MAX_SAMPLES:
        raise MeasurementError(f"at most {MAX_SAMPLES} odometry samples, got {len(poses)}")
    if not np.all(np.isfinite(poses)):
        raise MeasurementError("odometry poses must be finite")
    theta = np.unwrap(poses[:, 2])
    t0 = theta[0]
    offsets = poses[:, :2] - poses[0, :2]
    x, y = rotate_points(np.array([-t0]), offsets)
    return np.stack([x[0], y[0], theta - t0], axis=1)


def integrate_ticks(
    left_counts: FloatArray,
    right_counts: FloatArray,
    left_m_per_count: float,
    right_m_per_count: float,
    wheel_base_m: float,
) -> FloatArray:
    """Odometry poses (n, 3: x m, y m, theta rad, unwrapped) from cumulative
    wheel counts, starting at (0, 0, 0); each sample moves along the arc its
    two wheel travels describe (constant wheel speeds within a sample)."""
    left = np.asarray(left_counts, dtype=np.float64)
    right = np.asarray(right_counts, dtype=np.float64)
    if left.shape != right.shape or left.ndim != 1 or len(left) < 1:
        raise MeasurementError("left and right counts must be 1-d arrays of one length")
    if not (np.all(np.isfinite(left)) and np.all(np.isfinite(right))):
        raise MeasurementError("wheel counts must be finite")
    dl = np.diff(left) * left_m_per_count
    dr = np.diff(right) * right_m_per_count
    ds = 0.5 * (dl + dr)
    dtheta = (dr - dl) / wheel_base_m
    theta = np.concatenate([[0.0], np.cumsum(dtheta)])
    # the chord of each sample's arc, at its mean heading
    chord = ds * np.sinc(dtheta / (2.0 * math.pi))
    mid = theta[:-1] + 0.5 * dtheta
    x = np.concatenate([[0.0], np.cumsum(chord * np.cos(mid))])
    y = np.concatenate([[0.0], np.cumsum(chord * np.sin(mid))])
    return np.stack([x, y, theta], axis=1)


def _sample_kinds(rel: FloatArray, spin_radius_m: float) -> npt.NDArray[np.int64]:
    """Per sample step: 0 still, 2 in place, +1 forwards, -1 backwards.

    A step is judged with its neighbours: over the steps within
    :data:`JUDGE_M` of motion either side of it (distance plus
    :data:`JUDGE_RADIUS_M` x heading change), so that the counts of one
    sample (a spin whose wheels differ by a count, a twitch at a start) do
    not make a leg of their own."""
    ds, dtheta, window_ds, window_dtheta = step_windows(rel)
    # the same comparisons of the same floats as a loop over the steps would make
    still = (np.abs(ds) <= _TINY_M) & (np.abs(dtheta) <= _TINY_M)
    spin = np.abs(window_ds) < spin_radius_m * np.abs(window_dtheta)
    kinds: npt.NDArray[np.int64] = np.where(
        still, 0, np.where(spin, 2, np.where(window_ds > 0, 1, -1))
    ).astype(np.int64)
    return kinds


def step_windows(rel: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """Per odometry step of ``rel`` (n, 3, in the start frame): its signed
    distance along the mean heading (m) and heading change (rad), and their
    sums over the steps within :data:`JUDGE_M` of motion either side of it
    (what :func:`_sample_kinds` judges the step by)."""
    dx = np.diff(rel[:, 0])
    dy = np.diff(rel[:, 1])
    dtheta = np.diff(rel[:, 2])
    mid = rel[:-1, 2] + 0.5 * dtheta
    ds = np.cos(mid) * dx + np.sin(mid) * dy
    motion = np.concatenate([[0.0], np.cumsum(np.abs(ds) + JUDGE_RADIUS_M * np.abs(dtheta))])
    sum_ds = np.concatenate([[0.0], np.cumsum(ds)])
    sum_dtheta = np.concatenate([[0.0], np.cumsum(dtheta)])
    lo = np.searchsorted(motion, motion[:-1] - JUDGE_M, side="left")
    hi = np.searchsorted(motion, motion[1:] + JUDGE_M, side="right") - 1
    window_ds = sum_ds[hi] - sum_ds[lo]
    window_dtheta = sum_dtheta[hi] - sum_dtheta[lo]
    return ds, dtheta, window_ds, window_dtheta


def _segments(rel: FloatArray, bounds: CompressionBounds) -> list[tuple[int, int, int]]:
    """(first sample, last sample, kind) of each segment."""
    kind_array = _sample_kinds(rel, bounds.spin_radius_m)
    kinds: list[int] = kind_array.tolist()
    step_length = np.hypot(np.diff(rel[:, 0]), np.diff(rel[:, 1])).tolist()
    theta = rel[:, 2].tolist()
    segments: list[tuple[int, int, int]] = []
    start, kind, driven = 0, 0, 0.0
    for index in np.flatnonzero(kind_array).tolist():  # still steps change nothing
        step_kind = kinds[index]
        end = index + 1
        if kind == 0:
            kind = step_kind
        else:
            too_far = kind != 2 and (
                abs(theta[end] - theta[start]) > bounds.heading_step_rad
                or driven + step_length[index] > bounds.leg_max_m
            )
            if step_kind != kind or too_far:
                segments.append((start, index, kind))
                start, kind, driven = index, step_kind, 0.0
        driven += step_length[index]
    if kind != 0 and start < len(theta) - 1:
        segments.append((start, len(theta) - 1, kind))
    return segments


def _segment_steps(rel: FloatArray, first: int, last: int, kind: int) -> list[Step]:
    x0, y0, h0 = (float(v) for v in rel[first])
    x1, y1, h1 = (float(v) for v in rel[last])
    turned = h1 - h0
    turn_kind: TurnKind = "spin" if kind == 2 else "arc"
    chord = math.hypot(x1 - x0, y1 - y0)
    if chord <= _TINY_M:
        return [Turn(turned, turn_kind)] if turned != 0.0 else []
    direction = math.atan2(y1 - y0, x1 - x0)
    # in place (kind 2), the drift's sign follows the heading half-way through
    backwards = math.cos(direction - (h0 + 0.5 * turned)) < 0.0 if kind == 2 else kind == -1
    if backwards:
        direction += math.pi
    before = wrap_angle(direction - h0)
    after = turned - before
    steps: list[Step] = []
    if before != 0.0:
        steps.append(Turn(before, turn_kind))
    steps.append(Leg(-chord if backwards else chord))
    if after != 0.0:
        steps.append(Turn(after, turn_kind))
    return steps


def _merge_turns(steps: list[Step]) -> list[Step]:
    merged: list[Step] = []
    for step in steps:
        previous = merged[-1] if merged else None
        if isinstance(step, Turn) and isinstance(previous, Turn) and previous.kind == step.kind:
            angle = previous.angle_rad + step.angle_rad
            merged.pop()
            if angle != 0.0:
                merged.append(Turn(angle, step.kind))
            continue
        merged.append(step)
    return merged


def compress_odometry(
    poses: FloatArray, bounds: CompressionBounds | None = None, name: str = ""
) -> EncoderPath:
    """The encoder path of the odometry ``poses`` (n, 3: x m, y m, theta rad,
    in any odometry frame; headings may be wrapped if each sample turns less
    than pi), compressed into legs and turns (module docstring)."""
    bounds = bounds or CompressionBounds()
    rel = in_start_frame(poses)
    steps: list[Step] = []
    for first, last, kind in _segments(rel, bounds):
        steps.extend(_segment_steps(rel, first, last, kind))
    steps = _merge_turns(steps)
    if not any(isinstance(step, Leg) for step in steps):
        steps.append(Leg(PLACEHOLDER_LEG_M))
    return EncoderPath(tuple(steps), name=name)


def odometry_end_pose(poses: FloatArray) -> tuple[float, float, float]:
    """Where the odometry ends, seen from where it starts: (x m, y m, theta
    rad minus the multiple of 2 pi nearest the net turn), the convention of
    :meth:`EncoderPath.encoder_end_pose`."""
    rel = in_start_frame(poses)
    x, y, theta = (float(v) for v in rel[-1])
    winding = 2.0 * math.pi * round(theta / (2.0 * math.pi))
    return (x, y, theta - winding)


def path_family(path: EncoderPath) -> tuple[str, Direction]:
    """The family (``straight``, ``spin``, ``arc``, ``mixed``) and direction of
    a path, for the model checks' groups.

    - ``straight``: legs of one sign turning less than :data:`STRAIGHT_TURN_RAD`
      in all; ``forward`` or ``backward``;
    - ``spin``: turns in place, driving less than :data:`SPIN_DRIFT_M`;
    - ``arc``: curves of one sense, no turn in place above :data:`STRAIGHT_TURN_RAD`;
    - ``mixed``: anything else (a square of legs and spins, an S-curve);
      ``cw``/``ccw`` by the sign of the net turn when it is at least
      :data:`STRAIGHT_TURN_RAD`, else ``mixed``.
    """
    turns = [step for step in path.steps if isinstance(step, Turn)]
    spin_total = sum(abs(t.angle_rad) for t in turns if t.kind == "spin")
    arc_total = sum(abs(t.angle_rad) for t in turns if t.kind == "arc")
    net = path.net_turn_rad
    sense: Direction = "ccw" if net > 0 else "cw"
    legs = path.legs
    forward = float(legs.length_m[legs.sign > 0].sum())
    backward = float(legs.length_m[legs.sign < 0].sum())
    one_way = min(forward, backward) <= STRAIGHT_OTHER_WAY * (forward + backward)
    if spin_total + arc_total < STRAIGHT_TURN_RAD and one_way:
        return "straight", "forward" if forward >= backward else "backward"
    if spin_total >= STRAIGHT_TURN_RAD and path.distance_m < SPIN_DRIFT_M:
        return "spin", sense
    if spin_total < STRAIGHT_TURN_RAD and abs(net) >= 0.9 * arc_total:
        return "arc", sense
    if abs(net) >= STRAIGHT_TURN_RAD:
        return "mixed", sense
    return "mixed", "mixed"
