"""The per-trial check every measured pose change goes through before it is kept.

The engine (odohil/session/run/engine.py) hands each :class:`MeasuredPose`, from
any :class:`~odohil.session.measure.protocol.PoseSource`, to :func:`judge` with the
model's predictive distribution and what the encoders journaled. The test is
odohil/science/pose_selection.py's :func:`~odohil.science.pose_selection.pose_check`
(the slip check's test, on the pose): against the prediction, and the
distance from the start (and, for a source that saw the path, its farthest
point) against the encoders'.

- **doubtful** (beyond the slip check's level): the trial is kept, flagged,
  unless its source already tested it against the prediction (the tape's slip
  check, with its re-measures) or flagged it;
- **implausible** (beyond :data:`~odohil.science.pose_selection.IMPLAUSIBLE_SIGMAS`,
  or a distance off by more than a factor
  :data:`~odohil.science.pose_selection.SCALE_RATIO`): the measurement is
  wrong, not the robot. The engine voids the attempt and stops the session
  before the next motion, with the reason and its likely cause (a frozen
  stream, a unit error, a wrong rigid body); ``odohil resume`` redoes the
  trial once the measurement is fixed.

A pose its source flagged or found ambiguous is not judged again.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from odohil.driver.odometry import TrialMotion
from odohil.science.floor_marks import PoseDistribution
from odohil.science.pose_selection import (
    IMPLAUSIBLE_SIGMAS,
    SCALE_FLOOR_M,
    SLIP_LEVEL,
    PoseCheck,
    ScaleCheck,
    pose_check,
    pose_statistic,
)
from odohil.session.measure.protocol import MeasuredPose, Pose

__all__ = [
    "far_window",
    "judge",
]

UNIT_RATIOS = (
    (1000.0, "millimetres"),
    (100.0, "centimetres"),
    (1.0 / 0.0254, "inches"),
    (1.0 / 0.3048, "feet"),
)
"""Unit errors named: the measurement in that unit where metres are expected
(its distances that many times the true ones; headings are not scaled)."""
UNIT_FIT_GAIN = 100.0
"""A unit is named when the pose, its distances divided by the unit's factor,
fits the prediction this many times better (T) and is no longer implausible."""
_NEAR = math.log(1.25)
"""A ratio within this factor of one above names it."""
FROZEN_FRACTION = 0.1
"""A measured distance below this fraction of the encoders' says the
measurement did not follow the robot."""


@dataclass(frozen=True)
class Judgement:
    """What :func:`judge` decided.

    Attributes:
        measured: the pose to keep (flagged when doubtful), its ``details``
            holding the check's numbers (``check``).
        refusal: why the measurement is implausible ("" when it is kept).
    """

    measured: MeasuredPose
    refusal: str = ""


def far_window(motion: TrialMotion) -> tuple[float, float] | None:
    """Host times (s) of the first and last odometry sample of the motion at
    least half the farthest sample's distance from its start, or None when
    the farthest is within :data:`~odohil.science.pose_selection.SCALE_FLOOR_M`."""
    samples = (*motion.samples, motion.end)
    x0, y0 = motion.start.x_m, motion.start.y_m
    distances = [math.hypot(s.x_m - x0, s.y_m - y0) for s in samples]
    farthest = max(distances)
    if farthest <= SCALE_FLOOR_M:
        return None
    far = [s.host_time_s for s, d in zip(samples, distances, strict=True) if d >= farthest / 2]
    return (far[0], far[-1])


def encoder_excursion(trajectory: Sequence[Sequence[float]], end_pose: Pose) -> float:
    """The farthest the encoders put the robot from its start, m (rows t s,
    x m, y m, heading rad, as journaled; the end pose included)."""
    points = [math.hypot(row[1], row[2]) for row in trajectory if len(row) >= 3]
    return max([math.hypot(end_pose[0], end_pose[1]), *points])


def judge(
    trial: int,
    measured: MeasuredPose,
    predicted: PoseDistribution,
    encoder_end_pose: Pose,
    trajectory: Sequence[Sequence[float]] = (),
    closed: bool = False,
) -> Judgement:
    """Judge one measured pose change (see the module docstring). ``closed``:
    the path ends where it started (a square, a circle, a two-way design), so
    its end's distance from the start is noise on both sides and not judged
    for scale (its farthest point still is, when the source saw the path)."""
    if measured.ambiguous or measured.flagged:
        return Judgement(measured)
    excursion = None
    if measured.excursion_m is not None and trajectory:
        excursion = (measured.excursion_m, encoder_excursion(trajectory, encoder_end_pose))
    check = pose_check(measured.pose, measured.covariance, predicted, encoder_end_pose, excursion)
    if closed and check.scales and check.scales[0].off:
        check = replace(check, scales=(replace(check.scales[0], off=False), *check.scales[1:]))
    kept = replace(measured, details={**measured.details, "check": check.to_json()})
    if check.implausible:
        return Judgement(kept, refusal=_refusal(trial, check, measured, predicted))
    if check.doubtful and not measured.prediction_checked:
        kept = replace(kept, flagged=True, flag_reason=_doubt(check))
    return Judgement(kept)


def _doubt(check: PoseCheck) -> str:
    return (
        f"the trial does not fit the other trials and the encoders (T = "
        f"{check.statistic:.1f}, limit {check.limit:.1f} at level {SLIP_LEVEL:g})"
    )


def _refusal(
    trial: int, check: PoseCheck, measured: MeasuredPose, predicted: PoseDistribution
) -> str:
    off = [s for s in check.scales if s.off]
    scale = off[-1] if off else check.scales[0]  # the path's farthest point tells most
    cause = unit_error(measured, predicted, check.statistic) or likely_cause(scale, bool(off))
    source = measured.details.get("source")
    by = f"; measured by {source}" if source else ""
    return (
        f"trial {trial}: the measured pose change is implausible: {scale.what} "
        f"{scale.measured_m:.3f} m where the encoders say {scale.encoders_m:.3f} m: "
        f"{cause} (T = {check.statistic:.0f} against the model's "
        f"prediction and the encoders, doubtful beyond {check.limit:.1f}){by}. The attempt "
        "is void; fix the measurement and resume the session to redo the trial"
    )


def unit_error(measured: MeasuredPose, predicted: PoseDistribution, statistic: float) -> str:
    """The unit the measurement is likely in, when dividing its distances
    (or its heading, for degrees) by the unit's factor makes the pose fit the
    prediction ("" when none does)."""
    trials = [
        (
            np.array([1.0 / factor, 1.0 / factor, 1.0]),
            f"{unit}? (its distances divided by {factor:.4g}",
        )
        for factor, unit in UNIT_RATIOS
    ]
    trials.append((np.array([1.0, 1.0, math.pi / 180.0]), "theta in degrees? (as radians"))
    for scale, what in trials:
        pose = np.array(measured.pose) * scale
        cov = np.array(measured.covariance) * np.outer(scale, scale)
        fitted = pose_statistic(pose, cov, predicted)
        if fitted < IMPLAUSIBLE_SIGMAS**2 and fitted * UNIT_FIT_GAIN < statistic:
            return f"{what} it fits: T = {fitted:.1f})"
    return ""


def likely_cause(scale: ScaleCheck, off: bool) -> str:
    """The likely cause of an implausible measurement, in words."""
    if not off:
        return "a wrong rigid body, or was the robot moved by hand or did it slip?"
    if scale.measured_m < FROZEN_FRACTION * scale.encoders_m:
        return "frozen stream? (or a rigid body, or a robot, that did not move)"
    ratio = scale.ratio
    for factor, unit in UNIT_RATIOS:
        if math.isfinite(ratio) and abs(math.log(ratio / factor)) < _NEAR:
            return f"{unit}? (about {ratio:.4g} times the encoders' distance)"
    if scale.measured_m > scale.encoders_m:
        return "a unit error, or a wrong rigid body?"
    return "a wrong rigid body, or did the robot not follow its encoders?"
