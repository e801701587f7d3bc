"""Pose sources (odohil/session/measure/protocol.py) and the tape's distance sources.

Pose sources here:

- :class:`TapeSource`: floor-mark distances from a :class:`MeasurementSource`
  (below), turned into the pose change by the one pose-selection path
  (odohil/science/pose_selection.py) with rejections, the slip check,
  re-measures and an extra distance for ambiguous trials, every reading
  journaled through ``log``;
- :class:`TruthPoseSource`: the fake robot's true pose change from its truth
  channel, with seeded Gaussian pose noise;
- :class:`PoseFileSource`: a trial file of poses, read as poses;
- :class:`PathPoseSource`: a pose file or a general-path trial file serving
  driven general paths (odohil/session/trials/pose_file.py).

A :class:`MeasurementSource` is asked three things per trial attempt:
``mark_start`` once the robot is re-zeroed (the operator marks the floor under
every screw), ``mark_end`` once the motion is done (the end marks), then one
``distance`` per tape reading, in the robot description's order (same-screw
distances, then cross distances). Whatever ``mark_start``/``mark_end`` return
is journaled with the trial, so a resumed session hands the same data back.
A distance source sees each attempt as a
:class:`~odohil.session.measure.tape.records.TapeContext`: the generic context with
the distances' names and the tape's readings so far.

Sources here:

- :class:`OperatorSource`: a person with a tape, through an
  :class:`OperatorPrompts` implementation (the interactive wizard's);
- :class:`FakeTruthSource`: the fake robot's true pose (its side channel,
  behind the :class:`TruthReader` protocol), turned into distances by the
  forward model plus seeded Gaussian tape noise, for unattended runs and CI;
- :class:`RecordedSource`: distances recorded beforehand, one row per trial
  in trial order (e.g. from a trial file).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from odohil.errors import InconsistentMeasurementError, MeasurementError
from odohil.science import frames
from odohil.science.floor_marks import (
    MarkDistances,
    PosePrior,
    distance_labels,
    marks_from_pose,
    pose_covariance,
)
from odohil.science.paths import Design
from odohil.science.pose_selection import (
    ParameterBelief,
    predictive_pose,
    resolve_with_extra,
    select_pose,
    unmeasured_pair,
)
from odohil.science.robot_description import RobotDescription
from odohil.session.measure.protocol import (
    Covariance3,
    MeasuredPose,
    MeasurementLog,
    Pose,
    PoseSource,
    TrialContext,
)
from odohil.session.measure.tape.records import (
    ExtraDistance,
    Measurement,
    MeasurementsRejected,
    Remeasured,
    TapeContext,
)
from odohil.session.trials.pose_file import PoseRow, file_format, read_rows, row_problem
from odohil.session.trials.trial_file import Trial, read_trials

__all__ = [
    "FakeTruthSource",
    "MeasurementSource",
    "OperatorPrompts",
    "OperatorSource",
    "PathPoseSource",
    "PoseFileSource",
    "RecordedSource",
    "TapeContext",
    "TapeSource",
    "TrialContext",
    "TruthPoseSource",
    "TruthReader",
    "check_distance",
    "pose_source_from_file",
    "prediction",
    "recorded_source_from_file",
    "relative_true_pose",
]

MAX_REJECTIONS = 3
"""How many times one attempt's distances may be rejected before giving up."""
MAX_REMEASURES = 2
"""How many times the slip check may ask for a suspect distance again; a
trial it still doubts after that is journaled flagged."""


class MeasurementSource(Protocol):
    """Where distances come from (see the module docstring)."""

    def mark_start(self, ctx: TapeContext) -> Mapping[str, Any]:
        """The start marks are made now (the robot stands still, re-zeroed).

        Returns JSON data to journal with the trial (may be empty)."""
        ...

    def mark_end(self, ctx: TapeContext) -> Mapping[str, Any]:
        """The motion is over: the end marks are made now. Returns JSON data."""
        ...

    def distance(self, ctx: TapeContext, index: int) -> float:
        """Distance number ``index`` (label ``ctx.labels[index]``), metres.

        Raises MeasurementError when it cannot be had."""
        ...

    def rejected(self, ctx: TapeContext, rejection: InconsistentMeasurementError) -> None:
        """The distances of this attempt explain no rigid motion (``rejection``
        says why and names the suspect distances in its ``labels``); they will
        be asked for again (raise MeasurementError to give up instead)."""
        ...

    def remeasure(self, ctx: TapeContext, index: int, reason: str) -> float | None:
        """The slip check doubts the trial and suspects distance ``index``
        (``reason`` says why): that distance taken again, metres, or None to
        keep the value taken (the trial is then flagged)."""
        ...

    def extra_distance(
        self, ctx: TapeContext, pair: tuple[str, str], label: str, reason: str
    ) -> float | None:
        """The trial is ambiguous (``reason``): the cross distance from the start
        mark of screw ``pair[0]`` to the end mark of ``pair[1]`` (named
        ``label``), metres, or None when it cannot be had (the trial is then
        left out of the estimate)."""
        ...


class OperatorPrompts(Protocol):
    """The operator's side of a measurement (implemented by a user interface)."""

    def confirm_start_marks(self, ctx: TapeContext) -> None:
        """Ask the operator to mark the floor under every screw; return when done."""
        ...

    def confirm_end_marks(self, ctx: TapeContext) -> None:
        """Ask the operator to mark the end positions; return when done."""
        ...

    def ask_distance(self, ctx: TapeContext, index: int) -> float:
        """Ask for distance ``ctx.labels[index]``; return it in metres (the
        interface parses what was typed, once, and asks again until it is a
        distance)."""
        ...

    def show_rejection(self, ctx: TapeContext, rejection: InconsistentMeasurementError) -> None:
        """Tell the operator the distances are inconsistent and will be retaken
        (those ``rejection.labels`` names, or all when it names none)."""
        ...

    def ask_remeasure(self, ctx: TapeContext, index: int, reason: str) -> float | None:
        """Ask to measure distance ``ctx.labels[index]`` again (``reason``: the
        slip check's message); return it in metres, or None to keep the value."""
        ...

    def ask_extra_distance(self, ctx: TapeContext, label: str, reason: str) -> float | None:
        """Ask for one more cross distance, ``label`` (e.g. ``A start to C end``),
        because the trial is ambiguous (``reason``); return it in metres, or
        None when it cannot be measured."""
        ...


class OperatorSource:
    """A person with a tape, through :class:`OperatorPrompts`. The numbers the
    interface parsed are handed on as they are: :class:`TapeSource` checks
    every distance, from any source, once (:func:`check_distance`)."""

    def __init__(self, prompts: OperatorPrompts) -> None:
        self.prompts = prompts

    def mark_start(self, ctx: TapeContext) -> Mapping[str, Any]:
        """Wait for the operator's start marks."""
        self.prompts.confirm_start_marks(ctx)
        return {}

    def mark_end(self, ctx: TapeContext) -> Mapping[str, Any]:
        """Wait for the operator's end marks."""
        self.prompts.confirm_end_marks(ctx)
        return {}

    def distance(self, ctx: TapeContext, index: int) -> float:
        """Ask the operator for the distance, metres."""
        return self.prompts.ask_distance(ctx, index)

    def rejected(self, ctx: TapeContext, rejection: InconsistentMeasurementError) -> None:
        """Tell the operator."""
        self.prompts.show_rejection(ctx, rejection)

    def remeasure(self, ctx: TapeContext, index: int, reason: str) -> float | None:
        """Ask the operator to re-enter the suspect distance; None keeps it."""
        return self.prompts.ask_remeasure(ctx, index, reason)

    def extra_distance(
        self, ctx: TapeContext, pair: tuple[str, str], label: str, reason: str
    ) -> float | None:
        """Ask the operator for the named cross distance; None if skipped."""
        return self.prompts.ask_extra_distance(ctx, label, reason)


def prediction(ctx: TrialContext, description: RobotDescription) -> PosePrior:
    """The model's predictive distribution of the attempt's pose change: the
    engine's (``ctx.predicted``: at the live estimate, given the odometry),
    else from the description's ``[priors]`` and the encoders' end pose."""
    if ctx.predicted is not None:
        return ctx.predicted
    belief = ParameterBelief.from_priors(description.priors)
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


class TruthReader(Protocol):
    """The fake robot's side channel: its true pose now."""

    def true_pose(self) -> tuple[float, float, float]:
        """True (x m, y m, heading rad) in the robot's power-on frame."""
        ...


def relative_true_pose(
    start: Sequence[float], end: Sequence[float], winding_rad: float
) -> tuple[float, float, float]:
    """The true pose change from two true poses (x m, y m, heading rad): the end
    point in the start frame, and the heading change minus ``winding_rad``."""
    x, y, turned = frames.relative_pose(start, end)
    return (x, y, turned - winding_rad)


class FakeTruthSource:
    """Distances from the fake robot's true pose, with simulated tape noise.

    At ``mark_start`` and ``mark_end`` the true pose is read from the side
    channel and journaled (``true_pose``). Distances are the forward model of
    the true pose change plus independent N(0, ``sigma_m``^2) noise (the
    robot description's tape sigma by default), folded at 0. The noise of a
    trial attempt is drawn from a generator seeded by (seed, trial, attempt,
    rejections), so a resumed session measures exactly what the interrupted
    one would have.
    """

    def __init__(
        self,
        truth: TruthReader,
        description: RobotDescription,
        seed: int = 0,
        sigma_m: float | None = None,
    ) -> None:
        self.truth = truth
        self.description = description
        self.seed = seed
        self.sigma_m = description.sigma_m if sigma_m is None else sigma_m

    def mark_start(self, ctx: TapeContext) -> Mapping[str, Any]:
        """Journal the true start pose."""
        return {"true_pose": list(self.truth.true_pose())}

    def mark_end(self, ctx: TapeContext) -> Mapping[str, Any]:
        """Journal the true end pose."""
        return {"true_pose": list(self.truth.true_pose())}

    def true_pose_change(self, ctx: TrialContext) -> tuple[float, float, float]:
        """The attempt's true (dx m, dy m, dtheta rad), dtheta minus the winding."""
        return true_pose_change(ctx)

    def distance(self, ctx: TapeContext, index: int) -> float:
        """The noisy forward-model distance number ``index``, metres."""
        return self._draw(ctx, index, [self.seed, ctx.trial, ctx.attempt, ctx.rejections])

    def _draw(self, ctx: TapeContext, index: int, seed: list[int]) -> float:
        exact = marks_from_pose(self.description, self.true_pose_change(ctx)).as_array()
        rng = np.random.default_rng(seed)
        noisy = np.abs(exact + rng.normal(0.0, self.sigma_m, exact.size))
        return float(noisy[index])

    def rejected(self, ctx: TapeContext, rejection: InconsistentMeasurementError) -> None:
        """Nothing to do: the next draw differs (``rejections`` is in the seed)."""

    def remeasure(self, ctx: TapeContext, index: int, reason: str) -> float:
        """The suspect distance with a new noise draw (seeded by the attempt and
        the number of re-measures so far)."""
        seed = [self.seed, ctx.trial, ctx.attempt, ctx.rejections, 1 + ctx.remeasures]
        return self._draw(ctx, index, seed)

    def extra_distance(
        self, ctx: TapeContext, pair: tuple[str, str], label: str, reason: str
    ) -> None:
        """An unattended run takes no extra distances: the trial is left out."""
        return None


class RecordedSource:
    """Distances taken beforehand: row k (1-based) serves trial k of the plan
    (every attempt at it). Each row holds the distances in the robot
    description's order; with ``designs``, row k must be of trial k's design.
    """

    def __init__(
        self,
        rows: Sequence[Sequence[float]],
        description: RobotDescription,
        origin: str,
        designs: Sequence[Design] | None = None,
    ) -> None:
        labels = distance_labels(description)
        for number, row in enumerate(rows, start=1):
            if len(row) != len(labels):
                raise MeasurementError(
                    f"{origin}: row {number} has {len(row)} distances, "
                    f"the robot description needs {len(labels)} ({', '.join(labels)})"
                )
        self.rows = [tuple(float(v) for v in row) for row in rows]
        self.origin = origin
        self.designs = tuple(designs) if designs is not None else None

    def row_for(self, ctx: TapeContext) -> int:
        """The row used by trial ``ctx.trial`` (trial k uses row k - 1)."""
        return ctx.trial - 1

    def mark_start(self, ctx: TapeContext) -> Mapping[str, Any]:
        """Nothing to mark; journal which row serves the trial."""
        return {"row": self.row_for(ctx) + 1, "origin": self.origin}

    def mark_end(self, ctx: TapeContext) -> Mapping[str, Any]:
        """Nothing to mark."""
        return {}

    def distance(self, ctx: TapeContext, index: int) -> float:
        """Distance ``index`` of the trial's row."""
        row = self.row_for(ctx)
        if row >= len(self.rows):
            raise MeasurementError(
                f"{self.origin}: trial {ctx.trial} needs row {row + 1}, "
                f"the file has {len(self.rows)}"
            )
        if self.designs is not None and self.designs[row] != ctx.design:
            raise MeasurementError(
                f"{self.origin}: row {row + 1} is design {self.designs[row].label()}, "
                f"trial {ctx.trial} runs {ctx.design.label()}"
            )
        return self.rows[row][index]

    def remeasure(self, ctx: TapeContext, index: int, reason: str) -> None:
        """Recorded distances cannot be retaken: keep the value (the trial is flagged)."""
        return None

    def extra_distance(
        self, ctx: TapeContext, pair: tuple[str, str], label: str, reason: str
    ) -> None:
        """Recorded sessions have no extra distances: the trial is left out."""
        return None

    def rejected(self, ctx: TapeContext, rejection: InconsistentMeasurementError) -> None:
        """Recorded distances cannot be retaken."""
        raise MeasurementError(
            f"{self.origin}: row {self.row_for(ctx) + 1} (trial {ctx.trial}): {rejection}"
        )


def recorded_source_from_file(path: str | Path, description: RobotDescription) -> RecordedSource:
    """A :class:`RecordedSource` from a trial file: raw-mark rows give their
    distances; pose rows give the exact distances their pose change leaves
    (forward model). Row k serves trial k and must be of its design.

    Raises:
        TrialFileError: bad rows (all listed).
    """
    trials = read_trials(path, description)
    rows = [
        tuple(
            float(v)
            for v in (
                trial.marks.as_array()
                if trial.marks is not None
                else marks_from_pose(description, trial.pose_change).as_array()
            )
        )
        for trial in trials.trials
    ]
    return RecordedSource(
        rows, description, origin=str(path), designs=[t.design for t in trials.trials]
    )


# --- pose sources --------------------------------------------------------------


def _covariance(matrix: Any) -> Covariance3:
    rows = [tuple(float(v) for v in row) for row in matrix]
    return (
        (rows[0][0], rows[0][1], rows[0][2]),
        (rows[1][0], rows[1][1], rows[1][2]),
        (rows[2][0], rows[2][1], rows[2][2]),
    )


def _pose(values: Any) -> Pose:
    x, y, theta = (float(v) for v in values)
    return (x, y, theta)


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
            pose=_pose(solution.pose_change),
            covariance=_covariance(solution.cov),
            flagged=bool(slip_note),
            flag_reason=slip_note,
            note=solution.reason,
            clear_cut=bool(solution.clear_cut),
            ambiguous=selection.ambiguous,
            candidates=tuple(_pose(c.pose) for c in selection.plausible)
            if selection.ambiguous
            else (),
            details={"chi2": float(solution.chi2)},
            prediction_checked=True,
        )


class TruthPoseSource:
    """The fake robot's truth channel as a :class:`PoseSource`: the true pose
    change (journaled true start and end poses, minus the design's winding)
    plus independent Gaussian noise of standard deviations ``sigma`` (x m,
    y m, theta rad), drawn from a generator seeded by (seed, trial, attempt),
    so a resumed session measures what the interrupted one would have."""

    def __init__(
        self, truth: TruthReader, sigma: tuple[float, float, float], seed: int = 0
    ) -> None:
        if not all(math.isfinite(v) and v > 0 for v in sigma):
            raise MeasurementError(f"pose noise sigmas must be positive, got {sigma!r}")
        self.truth = truth
        self.sigma = sigma
        self.seed = seed

    def at_start(self, ctx: TrialContext) -> Mapping[str, Any]:
        """Journal the true start pose."""
        return {"true_pose": list(self.truth.true_pose())}

    def at_end(self, ctx: TrialContext) -> Mapping[str, Any]:
        """Journal the true end pose."""
        return {"true_pose": list(self.truth.true_pose())}

    def pose_change(self, ctx: TrialContext, log: MeasurementLog) -> MeasuredPose:
        """The noisy true pose change of the attempt."""
        exact = np.array(true_pose_change(ctx))
        rng = np.random.default_rng([self.seed, ctx.trial, ctx.attempt])
        sigma = np.array(self.sigma)
        noisy = exact + rng.normal(0.0, 1.0, 3) * sigma
        variances = sigma**2
        return MeasuredPose(
            pose=_pose(noisy),
            covariance=_covariance(np.diag(variances)),
            details={"source": "the fake robot's true pose with simulated noise"},
        )


class _FileRows:
    """What the pose sources of a file share: row k serves trial k (every
    attempt at it), and there is nothing to mark on the floor."""

    origin: str

    def at_start(self, ctx: TrialContext) -> Mapping[str, Any]:
        """Nothing to mark; journal which row serves the trial."""
        return {"row": ctx.trial, "origin": self.origin}

    def at_end(self, ctx: TrialContext) -> Mapping[str, Any]:
        """Nothing to mark."""
        return {}


class PoseFileSource(_FileRows):
    """A trial file of poses, read as poses: row k serves trial k of the plan
    (every attempt at it) and must be of its design. A row's covariance is the
    file's, else what the description's floor marks would give at that pose
    (:func:`~odohil.science.floor_marks.pose_covariance`)."""

    def __init__(self, trials: Sequence[Trial], origin: str, description: RobotDescription) -> None:
        self.trials = tuple(trials)
        self.origin = origin
        self.description = description

    def _row(self, ctx: TrialContext) -> Trial:
        row = ctx.trial - 1
        if row >= len(self.trials):
            raise MeasurementError(
                f"{self.origin}: trial {ctx.trial} needs row {row + 1}, "
                f"the file has {len(self.trials)}"
            )
        trial = self.trials[row]
        if trial.design != ctx.design:
            raise MeasurementError(
                f"{self.origin}: row {row + 1} is design {trial.design.label()}, "
                f"trial {ctx.trial} runs {ctx.design.label()}"
            )
        return trial

    def pose_change(self, ctx: TrialContext, log: MeasurementLog) -> MeasuredPose:
        """The trial's row as it stands in the file."""
        trial = self._row(ctx)
        cov = trial.pose_cov
        if cov is None:
            cov = pose_covariance(self.description, trial.pose_change)
        return MeasuredPose(
            pose=_pose(trial.pose_change),
            covariance=_covariance(cov),
            flagged=trial.flagged,
            flag_reason=trial.note,
            details={"source": f"{self.origin} line {trial.line}"},
        )


class PathPoseSource(_FileRows):
    """A pose file or a general-path trial file (odohil/session/trials/pose_file.py)
    as a :class:`PoseSource`: row k serves trial k of the plan (every attempt
    at it) and must be of its path (the pre-flight checked the whole file). A
    row's covariance is the file's, else what the description's floor marks
    would give at that pose."""

    def __init__(self, rows: Sequence[PoseRow], origin: str, description: RobotDescription) -> None:
        self.rows = tuple(rows)
        self.origin = origin
        self.description = description

    def _row(self, ctx: TrialContext) -> PoseRow:
        if ctx.trial > len(self.rows):
            raise MeasurementError(
                f"{self.origin}: trial {ctx.trial} needs row {ctx.trial}, "
                f"the file has {len(self.rows)}"
            )
        row = self.rows[ctx.trial - 1]
        problem = row_problem(row, ctx.design)
        if problem:
            raise MeasurementError(
                f"{self.origin}: row {row.number} (line {row.line}) cannot serve "
                f"trial {ctx.trial}: {problem}"
            )
        return row

    def pose_change(self, ctx: TrialContext, log: MeasurementLog) -> MeasuredPose:
        """The trial's row as it stands in the file.

        Raises:
            MeasurementError: the file has no row for the trial, or its row is
                of another path.
        """
        row = self._row(ctx)
        cov = row.cov if row.cov is not None else pose_covariance(self.description, row.pose)
        return MeasuredPose(
            pose=_pose(row.pose),
            covariance=_covariance(cov),
            details={"source": f"{self.origin} line {row.line}"},
        )


def true_pose_change(ctx: TrialContext) -> Pose:
    """The attempt's true (dx m, dy m, dtheta rad) from the journaled true start
    and end poses, dtheta minus the design's winding.

    Raises:
        MeasurementError: no true start and end pose were journaled.
    """
    try:
        start, end = ctx.start["true_pose"], ctx.end["true_pose"]
    except KeyError:
        raise MeasurementError(
            f"trial {ctx.trial}: no true start and end pose were journaled"
        ) from None
    return relative_true_pose(start, end, ctx.design.path().winding_rad)


def pose_source_from_file(path: str | Path, description: RobotDescription) -> PoseSource:
    """The pose source for a trial file: a file of poses is read as poses
    (:class:`PoseFileSource`; a pose file or a general-path trial file of
    driven general paths: :class:`PathPoseSource`); a file of raw distances
    goes through the tape and the floor-marks solver (:class:`TapeSource` over
    a :class:`RecordedSource`).

    Raises:
        TrialFileError: bad rows (all listed).
    """
    if file_format(path) != "trials":
        return PathPoseSource(read_rows(path), str(path), description)
    trials = read_trials(path, description)
    if trials.kind == "pose":
        return PoseFileSource(trials.trials, str(path), description)
    return TapeSource(recorded_source_from_file(path, description), description)
