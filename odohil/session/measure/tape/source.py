"""The tape as a pose source: floor-mark distances turned into the pose change.

:class:`TapeSource` asks a distance source (odohil/session/measure/tape/distances.py)
for the distances and turns them into the pose change by the one
pose-selection path (odohil/science/pose_selection.py), with rejections, the
slip check, re-measures and an extra distance for ambiguous trials, every
reading journaled through ``log`` (odohil/session/measure/tape/records.py).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from odohil.errors import InconsistentMeasurementError, MeasurementError
from odohil.science.floor_marks import (
    MarkDistances,
    PosePrior,
    distance_labels,
)
from odohil.science.pose_selection import (
    ParameterBelief,
    predictive_pose,
    resolve_with_extra,
    select_pose,
    unmeasured_pair,
)
from odohil.science.robot_description import RobotDescription
from odohil.session.measure.protocol import (
    MeasuredPose,
    MeasurementLog,
    TrialContext,
    as_covariance,
    as_pose,
)
from odohil.session.measure.tape.distances import MeasurementSource
from odohil.session.measure.tape.records import (
    ExtraDistance,
    Measurement,
    MeasurementsRejected,
    Remeasured,
    TapeContext,
)

__all__ = [
    "MAX_REJECTIONS",
    "MAX_REMEASURES",
    "TapeSource",
    "check_distance",
    "prediction",
]


MAX_REJECTIONS = 3
"""How many times one attempt's distances may be rejected before giving up."""


MAX_REMEASURES = 2
"""How many times the slip check may ask for a suspect distance again; a
trial it still doubts after that is journaled flagged."""


def prediction(ctx: TrialContext, description: RobotDescription) -> PosePrior:
    """The model's predictive distribution of the attempt's pose change: the
    engine's (``ctx.predicted``: at the live estimate, given the odometry),
    else from the description's ``[priors]`` and the encoders' end pose."""
    if ctx.predicted is not None:
        return ctx.predicted
    belief = ParameterBelief.from_priors(
        description.priors, turns_exact=description.robot.turns_exact
    )
    return predictive_pose(ctx.design, belief, ctx.encoder_end_pose)


def check_distance(value_m: float, label: str) -> float:
    """The one check of a measured distance, metres: finite and non-negative.
    Returns it unchanged (no conversion: sources hand over numbers).

    Raises:
        MeasurementError: not finite, or negative (naming ``label``).
    """
    if not math.isfinite(value_m):
        raise MeasurementError(f"{label}: {value_m!r} is not a finite number of metres")
    if value_m < 0:
        raise MeasurementError(f"{label}: a distance cannot be negative ({value_m!r} m)")
    return value_m


class TapeSource:
    """The tape with the floor-marks solver: a :class:`PoseSource` over a
    :class:`MeasurementSource` of distances.

    Each distance is journaled (``measurement``) as it is taken; the pose is
    chosen among those the marks allow by the one pose-selection path, scored
    against the odometry and ``ctx.predicted`` (the description's priors when
    absent). Distances no rigid motion explains are rejected and taken again
    (``measurements_rejected``, at most ``max_rejections`` times); when the
    slip check doubts the pose the suspect distance is taken again or kept
    (``remeasured``, at most ``max_remeasures`` times; a kept value flags the
    trial); an ambiguous trial asks for one extra cross distance
    (``extra_distance``) and is left out when it cannot be had.
    """

    def __init__(
        self,
        distances: MeasurementSource,
        description: RobotDescription,
        *,
        max_rejections: int = MAX_REJECTIONS,
        max_remeasures: int = MAX_REMEASURES,
    ) -> None:
        self.distances = distances
        self.description = description
        self.labels = distance_labels(description)
        self.max_rejections = max_rejections
        self.max_remeasures = max_remeasures

    def _labelled(self, ctx: TrialContext) -> TapeContext:
        """``ctx`` as the distance source sees it: with the names of the tape
        distances (its readings are this source's :class:`TapeReadings`)."""
        return TapeContext.of(ctx, self.labels)

    def at_start(self, ctx: TrialContext) -> Mapping[str, Any]:
        """The start marks (the distance source's journal data)."""
        return self.distances.mark_start(self._labelled(ctx))

    def at_end(self, ctx: TrialContext) -> Mapping[str, Any]:
        """The end marks (the distance source's journal data)."""
        return self.distances.mark_end(self._labelled(ctx))

    def _measure_missing(self, ctx: TapeContext, log: MeasurementLog) -> TapeContext:
        for index in range(len(ctx.measurements), len(self.labels)):
            label = self.labels[index]
            value = check_distance(self.distances.distance(ctx, index), label)
            ctx = self._labelled(log(Measurement(ctx.trial, ctx.attempt, index, value, label)))
        return ctx

    def pose_change(self, ctx: TrialContext, log: MeasurementLog) -> MeasuredPose:
        """Take the missing distances and choose the pose (see the class docstring).

        Raises:
            MeasurementError: the distances were rejected more than
                ``max_rejections`` times, or the distance source gave up.
        """
        return self._pose_change(self._labelled(ctx), log)

    def _pose_change(self, ctx: TapeContext, log: MeasurementLog) -> MeasuredPose:
        while True:
            ctx = self._measure_missing(ctx, log)
            marks = MarkDistances.of(self.description, ctx.measurements)
            end_pose = ctx.encoder_end_pose
            if end_pose is None:
                raise MeasurementError(f"trial {ctx.trial}: no odometry end pose to solve against")
            predicted = prediction(ctx, self.description)
            try:
                selection = select_pose(self.description, marks, end_pose, predicted)
            except InconsistentMeasurementError as exc:
                if ctx.rejections >= self.max_rejections:
                    raise MeasurementError(
                        f"trial {ctx.trial}: the distances were rejected "
                        f"{ctx.rejections + 1} times; last: {exc}"
                    ) from exc
                self.distances.rejected(ctx, exc)
                rejected = MeasurementsRejected(ctx.trial, ctx.attempt, reason=str(exc))
                ctx = self._labelled(log(rejected))
                continue
            selection = resolve_with_extra(self.description, marks, selection, ctx.extra)
            if selection.ambiguous and not ctx.extra:
                start, end = unmeasured_pair(self.description)
                label = f"{start} start to {end} end"
                value = self.distances.extra_distance(
                    ctx, (start, end), label, selection.solution.reason
                )
                if value is not None:
                    value = check_distance(value, label)
                    extra = ExtraDistance(ctx.trial, ctx.attempt, start, end, value, label)
                    ctx = self._labelled(log(extra))
                    continue
            slip = selection.slip
            if slip.tripped and not ctx.slip and ctx.remeasures < self.max_remeasures:
                reason = slip.message()
                previous = ctx.measurements[slip.suspect]
                value = self.distances.remeasure(ctx, slip.suspect, reason)
                if value is not None:
                    value = check_distance(value, self.labels[slip.suspect])
                remeasured = Remeasured(
                    ctx.trial,
                    ctx.attempt,
                    index=slip.suspect,
                    reason=reason,
                    kept=value is None,
                    previous_m=previous,
                    value_m=value,
                    label=self.labels[slip.suspect],
                )
                ctx = self._labelled(log(remeasured))
                if value is not None:
                    continue
            break
        solution = selection.solution
        slip_note = ctx.slip or (selection.slip.message() if selection.slip.tripped else "")
        return MeasuredPose(
            pose=as_pose(solution.pose_change),
            covariance=as_covariance(solution.cov),
            flagged=bool(slip_note),
            flag_reason=slip_note,
            note=solution.reason,
            clear_cut=bool(solution.clear_cut),
            ambiguous=selection.ambiguous,
            candidates=tuple(as_pose(c.pose) for c in selection.plausible)
            if selection.ambiguous
            else (),
            details={"chi2": float(solution.chi2)},
            prediction_checked=True,
        )
