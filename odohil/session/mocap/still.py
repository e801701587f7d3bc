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
- jumping: two successive poses differ by more than ``jump_sigmas`` times
  pose_sigma (sqrt 2 for the difference of two noisy poses folded in) in
  position or heading, a marker swap or a lost track;
- not still: the standard deviation of x, y or theta over the window is
  more than ``still_sigmas`` times the corresponding pose_sigma.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from odohil.errors import MeasurementError
from odohil.session.mocap.stream import PoseStream, StreamedPose, StreamStatus
from odohil.units import wrap_angle

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
        still_sigmas: largest standard deviation over the window, in pose_sigmas.
        jump_sigmas: largest step between successive poses, in pose_sigmas
            (times sqrt 2).
        first_pose_timeout_s: how long to wait for a first pose at all, s.
    """

    window_s: float = 0.5
    settle_s: float = 0.05
    min_poses: int = 5
    stale_s: float = STALE_S
    still_sigmas: float = 3.0
    jump_sigmas: float = 10.0
    first_pose_timeout_s: float = 3.0


@dataclass(frozen=True)
class StillPose:
    """A world pose taken at rest.

    Attributes:
        pose: (x m, y m, theta rad in (-pi, pi]) in the capture system's frame.
        n_poses: poses in the window.
        spread: standard deviations of x m, y m, theta rad over the window.
        t_span: the sender's ``t`` of the window's first and last pose, s.
        malformed: lines dropped since connecting (with the last reason).
    """

    pose: tuple[float, float, float]
    n_poses: int
    spread: tuple[float, float, float]
    t_span: tuple[float, float]
    malformed: int
    last_malformed: str = ""

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
    if not stream.wait_for_pose(criteria.first_pose_timeout_s):
        raise MeasurementError(_silent(stream.status(), url, stream.clock()))
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
            f"by this computer's clock){_closed(status)}{_dropped(status)}; is the robot "
            "still tracked?"
        )
    poses = stream.poses_between(begin, end)
    if len(poses) < criteria.min_poses:
        if status.closed:
            raise MeasurementError(f"motion capture {url}: {status.closed}{_dropped(status)}")
        raise MeasurementError(
            f"motion capture {url}: only {len(poses)} pose(s) arrived in the "
            f"{criteria.window_s:g} s still window (at least {criteria.min_poses} needed)"
            f"{_dropped(status)}; is the sender streaming at its full rate?"
        )
    return judge_window(poses, pose_sigma, criteria, url, status)


def judge_window(
    poses: Sequence[StreamedPose],
    pose_sigma: Sequence[float],
    criteria: StillCriteria,
    url: str,
    status: StreamStatus,
) -> StillPose:
    """The still pose of a window of poses, or MeasurementError (jumps, not still)."""
    sigma = np.array(pose_sigma, dtype=np.float64)
    xy = np.array([[p.x_m, p.y_m] for p in poses], dtype=np.float64)
    reference = poses[0].theta_rad
    theta = reference + np.array([wrap_angle(p.theta_rad - reference) for p in poses])
    values = np.column_stack([xy, theta])
    steps = np.abs(np.diff(values, axis=0))
    step_limit = criteria.jump_sigmas * math.sqrt(2.0) * sigma
    over = steps > step_limit
    if over.any():
        row, axis = (int(v) for v in np.argwhere(over)[0])
        gap_s = poses[row + 1].received_s - poses[row].received_s
        raise MeasurementError(
            f"motion capture {url}: the pose jumps by {_amount(steps[row, axis], axis)} in "
            f"{_AXES[axis]} between two poses {gap_s * 1e3:.0f} ms apart in the still window "
            f"(more than {criteria.jump_sigmas:g} x sqrt 2 x pose_sigma = "
            f"{_amount(step_limit[axis], axis)}); a marker swap or a lost track?"
        )
    spread = values.std(axis=0, ddof=1) if len(poses) > 1 else np.zeros(3)
    limit = criteria.still_sigmas * sigma
    if (spread > limit).any():
        axis = int(np.argmax(spread / limit))
        raise MeasurementError(
            f"motion capture {url}: the robot is not still: its {_AXES[axis]} spreads "
            f"{_amount(spread[axis], axis)} (standard deviation) over the "
            f"{criteria.window_s:g} s still window, more than {criteria.still_sigmas:g} x "
            f"pose_sigma = {_amount(limit[axis], axis)}; let it come to rest (or, if the "
            "capture noise is larger, raise [measurement] pose_sigma in the robot description)"
        )
    median = np.median(values, axis=0)
    return StillPose(
        pose=(float(median[0]), float(median[1]), wrap_angle(float(median[2]))),
        n_poses=len(poses),
        spread=(float(spread[0]), float(spread[1]), float(spread[2])),
        t_span=(poses[0].t_s, poses[-1].t_s),
        malformed=status.n_malformed,
        last_malformed=status.last_malformed,
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
    if not status.n_malformed:
        return ""
    return f" ({status.n_malformed} malformed line(s) dropped; last: {status.last_malformed})"
