"""Motion capture as a pose source: a tcp stream of world poses
(``--measure tcp://HOST:PORT``), still poses at a trial's start and end, and
the pose change with its covariance. See docs/motion-capture.md."""

from odohil.session.addresses import parse_tcp_url
from odohil.session.measure.mocap.change import pose_change_with_covariance
from odohil.session.measure.mocap.source import (
    MotionCaptureSource,
    pose_sigma_of,
    still_criteria_of,
)
from odohil.session.measure.mocap.still import (
    StillCriteria,
    StillPose,
    require_pose,
    take_still_pose,
)
from odohil.session.measure.mocap.stream import PoseStream, StreamedPose

__all__ = [
    "MotionCaptureSource",
    "PoseStream",
    "StillCriteria",
    "StillPose",
    "StreamedPose",
    "parse_tcp_url",
    "pose_change_with_covariance",
    "pose_sigma_of",
    "require_pose",
    "still_criteria_of",
    "take_still_pose",
]
