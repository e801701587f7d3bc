"""Trials of general paths: what a recorded log or a driven path hands the estimator.

A forth-and-back session names its trials by :class:`~odohil.science.paths.Design`;
a recording (odometry and ground truth logged on any path) cannot, so each of its
trials carries its own encoder path. This is the one value that crosses from the
log readers (odohil/session/trials/logs/) to the general-path estimator and validation.

Conventions (as :class:`~odohil.science.estimators.observations.Observation`):
the pose change is the true end pose in the start pose's frame, x and y in
metres, and the heading change in radians minus the path's
:attr:`~odohil.science.paths.EncoderPath.winding_rad`; the covariance is that of
the measurement (ground truth or tape), not of the robot.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

import numpy as np
import numpy.typing as npt

from odohil.errors import MeasurementError
from odohil.science.paths import EncoderPath, FloatArray

Direction = Literal["forward", "backward", "cw", "ccw", "mixed"]


def checked_measurement(
    where: str, pose_change: npt.ArrayLike, measurement_cov: npt.ArrayLike
) -> tuple[FloatArray, FloatArray]:
    """A trial's measured pose change (3,) and its covariance (3, 3), checked:
    finite, the covariance made symmetric and positive semi-definite.

    Raises:
        MeasurementError: naming ``where``.
    """
    pose = np.asarray(pose_change, dtype=np.float64).reshape(-1)
    if pose.shape != (3,) or not np.all(np.isfinite(pose)):
        raise MeasurementError(
            f"{where}: the pose change must be 3 finite numbers, got {pose_change!r}"
        )
    cov = np.asarray(measurement_cov, dtype=np.float64)
    if cov.shape != (3, 3) or not np.all(np.isfinite(cov)):
        raise MeasurementError(f"{where}: the measurement covariance must be finite 3x3")
    cov = 0.5 * (cov + cov.T)
    if np.linalg.eigvalsh(cov)[0] < -1e-12 * max(1.0, float(np.abs(cov).max())):
        raise MeasurementError(f"{where}: the measurement covariance is not positive semi-definite")
    return pose, cov


@dataclass(frozen=True)
class PathTrial:
    """One trial of a general path.

    Attributes:
        path: the encoder path (legs and turns) the odometry reports.
        pose_change: (3,) measured x (m), y (m) in the start frame and heading
            change (rad) minus ``path.winding_rad``.
        measurement_cov: (3, 3) covariance of the measured pose change
            (m^2, m rad, rad^2).
        source: where the trial came from (a file name), for messages.
        span_s: (start, end) time of the trial in its source, s, or None.
        trial: the trial's 1-based number in its trial set, or None.
        family: the path family the model checks group by (for example
            ``"straight"``, ``"spin"``, ``"arc"``, ``"square"``, a design label).
        direction: ``"forward"``/``"backward"`` for straight paths,
            ``"cw"``/``"ccw"`` for paths that turn, ``"mixed"`` otherwise.
    """

    path: EncoderPath
    pose_change: FloatArray
    measurement_cov: FloatArray = field(default_factory=lambda: np.zeros((3, 3)))
    source: str = ""
    span_s: tuple[float, float] | None = None
    trial: int | None = None
    family: str = "path"
    direction: Direction = "mixed"

    def __post_init__(self) -> None:
        pose, cov = checked_measurement(self.where(), self.pose_change, self.measurement_cov)
        object.__setattr__(self, "pose_change", pose)
        object.__setattr__(self, "measurement_cov", cov)

    def where(self) -> str:
        """``trial N of SOURCE (t0-t1 s)`` as far as it is known."""
        text = f"trial {self.trial}" if self.trial is not None else "a trial"
        if self.source:
            text += f" of {self.source}"
        if self.span_s is not None:
            text += f" ({self.span_s[0]:.2f}-{self.span_s[1]:.2f} s)"
        return text
