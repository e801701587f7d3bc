"""Pose sources that read a file: trial files of poses and pose files of paths.

- :class:`PoseFileSource`: a trial file of poses, read as poses;
- :class:`PathPoseSource`: a pose file or a general-path trial file serving
  driven general paths (odohil/session/trials/pose_file.py);
- :func:`pose_source_from_file`: the one of them a file's format asks for.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from odohil.errors import MeasurementError
from odohil.science.floor_marks import pose_covariance
from odohil.science.robot_description import RobotDescription
from odohil.session.measure.protocol import (
    MeasuredPose,
    MeasurementLog,
    PoseSource,
    TrialContext,
    as_covariance,
    as_pose,
)
from odohil.session.measure.tape.distances import recorded_source_from_file
from odohil.session.measure.tape.source import TapeSource
from odohil.session.trials.pose_file import PoseRow, file_format, read_rows, row_problem
from odohil.session.trials.trial_file import Trial, read_trials

__all__ = [
    "PathPoseSource",
    "PoseFileSource",
    "pose_source_from_file",
]


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
            pose=as_pose(trial.pose_change),
            covariance=as_covariance(cov),
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
            pose=as_pose(row.pose),
            covariance=as_covariance(cov),
            details={"source": f"{self.origin} line {row.line}"},
        )


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
