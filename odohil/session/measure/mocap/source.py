"""``MotionCaptureSource``: a :class:`~odohil.session.measure.protocol.PoseSource`
reading world poses from a motion-capture stream (``--measure tcp://HOST:PORT``).

At a trial's start and end (robot at rest) it takes a still pose
(odohil/session/measure/mocap/still.py) and returns it as journal data; the pose
change is computed from the journaled poses only (``ctx.start``/``ctx.end``),
so a resumed session measures the same, with the covariance of
odohil/session/measure/mocap/change.py from the robot description's
``[measurement] pose_sigma`` (each pose: diag(sigma_x^2, sigma_y^2, sigma_theta^2),
world axes).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from odohil.errors import RobotDescriptionError
from odohil.science.robot_description import RobotDescription
from odohil.session.measure.mocap.change import pose_change_with_covariance
from odohil.session.measure.mocap.still import StillCriteria, StillPose, take_still_pose
from odohil.session.measure.mocap.stream import PoseStream
from odohil.session.measure.protocol import MeasuredPose, MeasurementLog, TrialContext

MIN_PATH_FRAMES = 5
"""Fewest frames, while the encoders put the robot far from its start, for
the farthest point the stream saw to be reported."""


def still_criteria_of(description: RobotDescription) -> StillCriteria:
    """The still window's criteria: the description's ``[measurement]
    still_window_s`` as the window's length when it gives one, else the defaults."""
    if description.still_window_s is None:
        return StillCriteria()
    return StillCriteria(window_s=description.still_window_s)


def pose_sigma_of(description: RobotDescription, url: str) -> tuple[float, float, float]:
    """The description's pose_sigma, or RobotDescriptionError saying it is
    needed for ``url``."""
    if description.pose_sigma is None:
        raise RobotDescriptionError(
            f"--measure {url}: motion capture needs the standard deviations of one still "
            "pose in the robot description: [measurement] pose_sigma = "
            "[sigma_x_m, sigma_y_m, sigma_theta_rad] (docs/motion-capture.md)"
        )
    return description.pose_sigma


class MotionCaptureSource:
    """Trial pose changes from still poses of a motion-capture stream.

    Args:
        stream: the open :class:`PoseStream` (the caller closes it).
        pose_sigma: one still pose's standard deviations (x m, y m, theta rad).
        criteria: the still window and its thresholds.
    """

    def __init__(
        self,
        stream: PoseStream,
        pose_sigma: Sequence[float],
        criteria: StillCriteria | None = None,
    ) -> None:
        self.stream = stream
        self.pose_sigma = (float(pose_sigma[0]), float(pose_sigma[1]), float(pose_sigma[2]))
        self.criteria = criteria or StillCriteria()

    def pose_cov(self) -> Any:
        """One still pose's covariance, diagonal (m^2, m^2, rad^2)."""
        return np.diag(np.square(np.array(self.pose_sigma, dtype=np.float64)))

    def still(self) -> StillPose:
        """A still pose now (MeasurementError when the stream cannot give one)."""
        return take_still_pose(self.stream, self.pose_sigma, self.criteria)

    def at_start(self, ctx: TrialContext) -> Mapping[str, Any]:
        """The still pose at the trial's start, as journal data; from here the
        stream tracks how far the robot goes from it."""
        still = self.still()
        self.stream.track_from(still.pose[0], still.pose[1])
        return still.to_json()

    def at_end(self, ctx: TrialContext) -> Mapping[str, Any]:
        """The still pose at the trial's end, as journal data, with the
        farthest the stream saw the robot from its start while the encoders
        put it far (``ctx.far_s``): ``excursion_m``, over ``path_frames``
        frames, when at least :data:`MIN_PATH_FRAMES` arrived then (a
        fast-forwarded fake robot may pass between two frames)."""
        data = self.still().to_json()
        if ctx.far_s is not None:
            excursion, frames = self.stream.excursion_between(*ctx.far_s)
            if excursion is not None and frames >= MIN_PATH_FRAMES:
                data["excursion_m"] = excursion
                data["path_frames"] = frames
        return data

    def pose_change(self, ctx: TrialContext, log: MeasurementLog) -> MeasuredPose:
        """The end still pose in the start still pose's frame, with its covariance."""
        where = f"trial {ctx.trial}"
        start = StillPose.pose_of(ctx.start, f"{where} start")
        end = StillPose.pose_of(ctx.end, f"{where} end")
        cov = self.pose_cov()
        change, change_cov = pose_change_with_covariance(start, end, cov, cov)
        excursion = ctx.end.get("excursion_m")
        rows = tuple(tuple(float(v) for v in row) for row in change_cov)
        return MeasuredPose(
            pose=change,
            covariance=(
                (rows[0][0], rows[0][1], rows[0][2]),
                (rows[1][0], rows[1][1], rows[1][2]),
                (rows[2][0], rows[2][1], rows[2][2]),
            ),
            details={
                "source": (
                    f"motion capture {self.stream.url}: still poses of "
                    f"{ctx.start.get('n_poses', '?')} and {ctx.end.get('n_poses', '?')} frames"
                )
            },
            excursion_m=float(excursion) if isinstance(excursion, int | float) else None,
        )
