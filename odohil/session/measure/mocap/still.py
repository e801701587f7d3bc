"""The still pose: one world pose of a robot at rest, from a short window of
the motion-capture stream, or a MeasurementError that says what is wrong.

The window starts ``settle_s`` after the call (frames the sender captured
before the robot came to rest are still in flight) and lasts ``window_s``, on
this computer's monotonic clock. The pose is the median of x and of y, and
the circular median of theta (the median of the headings unwrapped around
the first one). The window is refused when the stream is

- silent: no pose arrived since connecting, or too few in the window;
- stale: the newest pose arrived more than ``stale_s`` (1 s) ago;
- closed: the sender hung up;
- jumping: two successive poses differ, in x, y or theta, by more than
  ``jump_sigmas`` x sqrt 2 times the larger of pose_sigma and the frame noise
  (a marker swap or a lost track);
- not still: the medians of the window's two halves differ, in x, y or
  theta, by more than ``still_sigmas`` times pose_sigma and by more than
  ``chance_sigmas`` times what the frame noise explains (the robot moves).

pose_sigma is the uncertainty of a still pose (a median over many frames),
usually well below the frame-to-frame jitter, so the window's spread itself
is not held against it: the drift between its halves is.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from odohil.errors import MeasurementError
from odohil.session.measure.mocap.stream import PoseStream, StreamedPose, StreamStatus
from odohil.units import angle_near, wrap_angle

STALE_S = 1.0
"""A stream whose newest pose is older than this (host clock, s) is stale."""


@dataclass(frozen=True)
class StillCriteria:
    """How a still pose is taken and judged.

    Attributes:
        window_s: length of the still window, s (host clock).
        settle_s: wait before the window starts, s.
        min_poses: fewest poses the window must hold.
        stale_s: the newest pose may be at most this old, s.
        still_sigmas: largest drift between the window's halves, in pose_sigmas.
        chance_sigmas: ... and in standard deviations of that drift by chance.
        jump_sigmas: largest step between successive poses, in the larger of
            pose_sigma and the frame noise (times sqrt 2).
        first_pose_timeout_s: how long to wait for a first pose at all, s.
    """

    window_s: float = 0.5
    settle_s: float = 0.1
    min_poses: int = 5
    stale_s: float = STALE_S
    still_sigmas: float = 5.0
    chance_sigmas: float = 6.0
    jump_sigmas: float = 10.0
    first_pose_timeout_s: float = 3.0


@dataclass(frozen=True)
class StillPose:
    """A world pose taken at rest.

    Attributes:
        pose: (x m, y m, theta rad in (-pi, pi]) in the capture system's frame.
        n_poses: poses in the window.
        spread: the frame noise of x m, y m, theta rad over the window
            (robust standard deviation from successive differences).
        t_span: the sender's ``t`` of the window's first and last pose, s.
        malformed: lines dropped since connecting (with the last reason).
        bad_time_stamps: frames dropped for their time stamp since connecting
            (with the last reason).
    """

    pose: tuple[float, float, float]
    n_poses: int
    spread: tuple[float, float, float]
    t_span: tuple[float, float]
    malformed: int
    last_malformed: str = ""
    bad_time_stamps: int = 0
    last_bad_time_stamp: str = ""

    def to_json(self) -> dict[str, Any]:
        """The JSON object journaled with the trial."""
        data: dict[str, Any] = {
            "pose": list(self.pose),
            "n_poses": self.n_poses,
            "spread": list(self.spread),
            "t_span": list(self.t_span),
            "malformed": self.malformed,
        }
        if self.last_malformed:
            data["last_malformed"] = self.last_malformed
        if self.bad_time_stamps:
            data["bad_time_stamps"] = self.bad_time_stamps
            data["last_bad_time_stamp"] = self.last_bad_time_stamp
        return data

    @staticmethod
    def pose_of(data: Mapping[str, Any], where: str) -> tuple[float, float, float]:
        """The pose journaled by :meth:`to_json` (MeasurementError naming ``where``)."""
        try:
            x, y, theta = (float(v) for v in data["pose"])
        except (KeyError, TypeError, ValueError):
            raise MeasurementError(f"{where}: no motion-capture still pose was journaled") from None
        if not all(math.isfinite(v) for v in (x, y, theta)):
            raise MeasurementError(f"{where}: the journaled still pose is not finite")
        return (x, y, theta)


def take_still_pose(
    stream: PoseStream,
    pose_sigma: Sequence[float],
    criteria: StillCriteria | None = None,
    sleep: Callable[[float], None] = time.sleep,
) -> StillPose:
    """Wait for the still window and judge it (see the module docstring).

    Args:
        stream: the open pose stream.
        pose_sigma: (x m, y m, theta rad), one still pose's standard deviations.
        criteria: window and thresholds.

    Raises:
        MeasurementError: silent, stale, closed, jumping or not still (the
            message names the stream's URL and the numbers).
    """
    criteria = criteria or StillCriteria()
    url = stream.url
    require_pose(stream, criteria.first_pose_timeout_s)
    begin = stream.clock() + criteria.settle_s
    end = begin + criteria.window_s
    while (left := end - stream.clock()) > 0:
        sleep(left)
    status = stream.status()
    now = stream.clock()
    if status.last_received_s is not None and now - status.last_received_s > criteria.stale_s:
        raise MeasurementError(
            f"motion capture {url}: stale stream: the newest pose arrived "
            f"{now - status.last_received_s:.2f} s ago (more than {criteria.stale_s:g} s, "
            f"by this computer's clock){_closed(status)}{_dropped(status)}; "
            f"{'is the robot still tracked?' if not status.n_bad_time else _rate_hint(status)}"
        )
    poses = stream.poses_between(begin, end)
    if len(poses) < criteria.min_poses:
        if status.closed:
            raise MeasurementError(f"motion capture {url}: {status.closed}{_dropped(status)}")
        raise MeasurementError(
            f"motion capture {url}: only {len(poses)} pose(s) arrived in the "
            f"{criteria.window_s:g} s still window (at least {criteria.min_poses} needed)"
            f"{_dropped(status)}; {_rate_hint(status)}"
        )
    return judge_window(poses, pose_sigma, criteria, url, status)


def require_pose(stream: PoseStream, timeout_s: float) -> None:
    """Return once the stream has delivered a pose; MeasurementError (silent or
    closed, naming the URL) when none arrives within ``timeout_s``."""
    if not stream.wait_for_pose(timeout_s):
        raise MeasurementError(_silent(stream.status(), stream.url, stream.clock()))


def judge_window(
    poses: Sequence[StreamedPose],
    pose_sigma: Sequence[float],
    criteria: StillCriteria,
    url: str,
    status: StreamStatus,
) -> StillPose:
    """The still pose of a window of poses, or MeasurementError (jumps, not still).

    The frame noise is estimated per axis from the successive differences,
    robustly (1.4826 x their median absolute deviation / sqrt 2), so that
    neither a jump nor a slow drift inflates it.
    """
    sigma = np.array(pose_sigma, dtype=np.float64)
    xy = np.array([[p.x_m, p.y_m] for p in poses], dtype=np.float64)
    reference = poses[0].theta_rad
    theta = angle_near(np.array([p.theta_rad for p in poses], dtype=np.float64), reference)
    values = np.column_stack([xy, theta])
    steps = np.diff(values, axis=0)
    deviation = np.abs(steps - np.median(steps, axis=0))
    frame_noise = 1.4826 * np.median(deviation, axis=0) / math.sqrt(2.0)
    step_limit = criteria.jump_sigmas * math.sqrt(2.0) * np.maximum(sigma, frame_noise)
    over = np.abs(steps) > step_limit
    if over.any():
        row, axis = (int(v) for v in np.argwhere(over)[0])
        gap_s = poses[row + 1].received_s - poses[row].received_s
        raise MeasurementError(
            f"motion capture {url}: the pose jumps by {_amount(abs(steps[row, axis]), axis)} in "
            f"{_AXES[axis]} between two poses {gap_s * 1e3:.0f} ms apart in the still window "
            f"(more than {criteria.jump_sigmas:g} x sqrt 2 x the larger of pose_sigma and the "
            f"frame noise = {_amount(step_limit[axis], axis)}); a marker swap or a lost track?"
        )
    half = len(poses) // 2
    drift = np.abs(np.median(values[half:], axis=0) - np.median(values[:half], axis=0))
    # the halves' medians differ by about 1.2533 x frame noise x 2 / sqrt(n) by chance alone
    chance = 1.2533 * frame_noise * 2.0 / math.sqrt(len(poses))
    drift_limit = np.maximum(criteria.still_sigmas * sigma, criteria.chance_sigmas * chance)
    if (drift > drift_limit).any():
        axis = int(np.argmax(drift / drift_limit))
        allowed = _amount(criteria.still_sigmas * sigma[axis], axis)
        raise MeasurementError(
            f"motion capture {url}: the robot is not still: its {_AXES[axis]} moved "
            f"{_amount(drift[axis], axis)} between the two halves of the "
            f"{criteria.window_s:g} s still window (medians), more than "
            f"{criteria.still_sigmas:g} x pose_sigma = {allowed} "
            "and more than the frame noise explains; let it come to rest"
        )
    median = np.median(values, axis=0)
    return StillPose(
        pose=(float(median[0]), float(median[1]), wrap_angle(float(median[2]))),
        n_poses=len(poses),
        spread=(float(frame_noise[0]), float(frame_noise[1]), float(frame_noise[2])),
        t_span=(poses[0].t_s, poses[-1].t_s),
        malformed=status.n_malformed,
        last_malformed=status.last_malformed,
        bad_time_stamps=status.n_bad_time,
        last_bad_time_stamp=status.last_bad_time,
    )


_AXES = ("x", "y", "theta")


def _amount(value: float, axis: int) -> str:
    return f"{value * 1e3:.3g} mm" if axis < 2 else f"{math.degrees(value):.3g} deg"


def _silent(status: StreamStatus, url: str, now: float) -> str:
    waited = now - status.connected_s
    what = status.closed or f"silent stream: no pose in the {waited:.1f} s since connecting"
    return (
        f"motion capture {url}: {what}{_dropped(status)}; is the sender streaming "
        'newline-delimited JSON poses {"t": s, "x": m, "y": m, "theta": rad}?'
    )


def _closed(status: StreamStatus) -> str:
    return f"; {status.closed}" if status.closed else ""


def _dropped(status: StreamStatus) -> str:
    dropped = []
    if status.n_malformed:
        dropped.append(
            f"{status.n_malformed} malformed line(s) dropped; last: {status.last_malformed}"
        )
    if status.n_bad_time:
        dropped.append(
            f"{status.n_bad_time} frame(s) with a bad time stamp dropped; last: "
            f"{status.last_bad_time}"
        )
    return f" ({'; '.join(dropped)})" if dropped else ""


def _rate_hint(status: StreamStatus) -> str:
    """What to check when too few poses arrive: the stamps when frames were
    dropped for them, else the rate."""
    if status.n_bad_time:
        return "does the sender stamp its frames with one steady clock, in seconds?"
    return "is the sender streaming at its full rate?"
