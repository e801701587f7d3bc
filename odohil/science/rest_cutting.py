"""Cutting a recording into trials at rest, and a trial's measured pose change.

A trial of a recorded log starts and ends with the robot standing still, so
that its start and end poses can be taken from the ground truth averaged over
the rest (motion capture jitters, a still robot's mean does not).

Cutting at rest (a log without a given cut) needs both the odometry and the
ground truth still (:func:`still_mask`): the mean pose over
:data:`REST_WINDOW_S` before a sample and the mean over the same time after
it differ by less than :data:`REST_SPEED_M_PER_S` (position) and
:data:`REST_TURN_RAD_PER_S` (heading) times the time between the two
windows' centres. Means, so that jitter averages out; both ways, so that a
rest neither reaches into the motion that follows it nor begins before the
motion before it has ended. A rest that separates two trials lasts at least
:data:`MIN_REST_S`.

When the cut is given (a ``trial`` column, one file per trial) only the
rests at the trial's two ends are needed (:func:`edge_rests`): the samples
from the first (back from the last) whose *odometry* stays within
:data:`EDGE_MOVE_M` and :data:`EDGE_TURN_RAD` of it, for at least
:data:`MIN_EDGE_REST_S`. The odometry alone decides there because encoders
report exact zeros at rest, while the optiodom ground truth jitters up to
14 mrad peak to peak in the last half second of some runs.

The thresholds, in SI, and why (``ImportOptions`` in odohil/session/trials/logs/
lets a user change the durations):

- 0.006 m/s and 0.08 rad/s over 0.25 s windows (1.5 mm and 20 mrad between
  the window means): an encoder twitch of one count (0.09 mm on the optiodom
  robot, 0.44 mm on a Create 2) and motion-capture jitter (0.06 mm and
  0.7 mrad at rest in most optiodom samples, 7 mrad in its worst; a few tenths
  of a mm elsewhere) stay well inside them; the slowest motion of the data
  set (0.047 m/s straight, 0.31 rad/s in place) is 4 to 8 times faster.
- :data:`MIN_REST_S` = 1.0 s between trials, so that a pause at the corner of
  a square (0.1-0.3 s in the optiodom data) does not cut it;
  docs/recording.md asks for 2 s.
- :data:`MIN_EDGE_REST_S` = 0.2 s at the ends of a given cut (4 samples at
  20 Hz; the optiodom runs rest 0.2-1.3 s at their ends): the cut is known,
  only the pose needs averaging. 1.5 mm and 10 mrad for the odometry there:
  a few counts of twitch.

The pose change (:func:`measured_change`) is the end rest's mean pose in the
frame of the start rest's mean pose, x and y in metres, its heading change
taken within pi of the encoder's net turn and reported minus the encoder
path's winding (:class:`~odohil.science.path_trials.PathTrial`); its
covariance propagates each rest pose's covariance through
:func:`~odohil.science.frames.relative_pose_jacobians`.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from odohil.errors import MeasurementError
from odohil.science.frames import relative_pose, relative_pose_jacobians
from odohil.science.paths import FloatArray
from odohil.units import angle_near, circular_mean, wrap_angles

BoolArray = npt.NDArray[np.bool_]

REST_WINDOW_S = 0.25
"""Time either side of a sample over which stillness is judged, s."""
REST_SPEED_M_PER_S = 0.006
"""Largest speed (position change over the window / window) of a still robot, m/s."""
REST_TURN_RAD_PER_S = 0.08
"""Largest turn rate of a still robot, rad/s."""
MIN_REST_S = 1.0
"""Shortest rest that separates two trials, s."""
MIN_EDGE_REST_S = 0.2
"""Shortest rest at the start and end of a trial whose cut is given, s."""
EDGE_MOVE_M = 0.0015
"""How far the odometry may move during a rest at a trial's edge, m."""
EDGE_TURN_RAD = 0.01
"""How far the odometry may turn during a rest at a trial's edge, rad."""


def still_mask(
    t_s: FloatArray,
    poses: FloatArray,
    *,
    window_s: float = REST_WINDOW_S,
    speed_m_per_s: float = REST_SPEED_M_PER_S,
    turn_rad_per_s: float = REST_TURN_RAD_PER_S,
) -> BoolArray:
    """True where the poses (n, 3: x m, y m, theta rad, wrapped or not;
    NaN where missing) stand still at times ``t_s`` (n,, increasing, s): the
    mean pose over the window before the sample and the mean over the window
    after it differ by less than the speeds allow over one window (module
    docstring); means, so that motion-capture jitter averages out. A sample
    with a missing pose in either window is not still."""
    t = np.asarray(t_s, dtype=np.float64)
    p = np.asarray(poses, dtype=np.float64)
    n = len(t)
    if n == 0:
        return np.zeros(0, dtype=np.bool_)
    # headings made continuous where present (a still robot's heading may straddle +-pi)
    theta = p[:, 2].copy()
    present = np.all(np.isfinite(p), axis=1)
    if present.any():
        theta[present] = np.unwrap(theta[present])
    values = np.stack([p[:, 0], p[:, 1], theta], axis=1)
    values[~present] = 0.0
    sums = np.vstack([np.zeros((1, 3)), np.cumsum(values, axis=0)])
    missing = np.concatenate([[0], np.cumsum(~present)])
    index = np.arange(n)
    back = np.searchsorted(t, t - window_s, side="left")
    ahead = np.searchsorted(t, t + window_s, side="right")
    before = (sums[index + 1] - sums[back]) / (index + 1 - back)[:, None]
    after = (sums[ahead] - sums[index]) / (ahead - index)[:, None]
    times = np.concatenate([[0.0], np.cumsum(t - t[0])])
    # the time between the two windows' centres (shorter at the recording's ends)
    span = (times[ahead] - times[index]) / (ahead - index) - (times[index + 1] - times[back]) / (
        index + 1 - back
    )
    gaps = (missing[index + 1] - missing[back]) + (missing[ahead] - missing[index])
    d_xy = np.hypot(after[:, 0] - before[:, 0], after[:, 1] - before[:, 1])
    d_theta = np.abs(after[:, 2] - before[:, 2])
    result: BoolArray = (
        (gaps == 0) & (d_xy <= speed_m_per_s * span) & (d_theta <= turn_rad_per_s * span)
    )
    return result


def rest_windows(t_s: FloatArray, still: BoolArray, min_rest_s: float) -> list[tuple[int, int]]:
    """(first, last) sample indices of each maximal run of still samples that
    lasts at least ``min_rest_s`` (t[last] - t[first], s), in time order."""
    t = np.asarray(t_s, dtype=np.float64)
    flags = np.concatenate([[0], np.asarray(still, dtype=np.int8), [0]])
    edges = np.flatnonzero(np.diff(flags))
    windows = []
    for first, stop in zip(edges[::2].tolist(), edges[1::2].tolist(), strict=True):
        last = stop - 1
        if t[last] - t[first] >= min_rest_s:
            windows.append((first, last))
    return windows


def edge_rests(
    t_s: FloatArray,
    odometry: FloatArray,
    min_rest_s: float,
    *,
    move_m: float = EDGE_MOVE_M,
    turn_rad: float = EDGE_TURN_RAD,
) -> tuple[tuple[int, int] | None, tuple[int, int] | None]:
    """The rests at the very start and end of a trial whose cut is given, as
    (first, last) sample indices: the longest run of samples from the first
    (back from the last) whose odometry (n, 3) stays within ``move_m`` and
    ``turn_rad`` of the first (last) sample's. Each is None when it lasts less
    than ``min_rest_s`` or the two would meet (the robot never moves)."""
    t = np.asarray(t_s, dtype=np.float64)
    p = np.asarray(odometry, dtype=np.float64)

    def near(reference: int) -> np.ndarray:
        d_xy = np.hypot(p[:, 0] - p[reference, 0], p[:, 1] - p[reference, 1])
        d_theta = np.abs(wrap_angles(p[:, 2] - p[reference, 2]))
        return np.asarray((d_xy <= move_m) & (d_theta <= turn_rad), dtype=bool)

    if len(t) < 2:
        return None, None
    at_start, at_end = near(0), near(len(t) - 1)
    if at_start.all():
        return None, None
    start_last = int(np.argmin(at_start)) - 1
    end_first = len(t) - int(np.argmin(at_end[::-1]))
    start = (0, start_last) if t[start_last] - t[0] >= min_rest_s else None
    end = (end_first, len(t) - 1) if t[-1] - t[end_first] >= min_rest_s else None
    if start is not None and end is not None and end_first <= start_last:
        return None, None
    return start, end


def mean_pose(poses: FloatArray) -> tuple[float, float, float]:
    """The mean of still poses (n, 3): x and y averaged (m), the heading as
    the circular mean (rad, in (-pi, pi])."""
    p = np.asarray(poses, dtype=np.float64)
    if len(p) == 0:
        raise MeasurementError("a rest needs at least one pose")
    return (float(p[:, 0].mean()), float(p[:, 1].mean()), circular_mean(p[:, 2]))


def pose_scatter(poses: FloatArray) -> tuple[float, float, float]:
    """Standard deviations of still poses (n, 3) about their mean: x m, y m,
    theta rad (0 for one pose)."""
    p = np.asarray(poses, dtype=np.float64)
    if len(p) < 2:
        return (0.0, 0.0, 0.0)
    centre = mean_pose(p)
    dtheta = wrap_angles(p[:, 2] - centre[2])
    return (
        float(p[:, 0].std(ddof=1)),
        float(p[:, 1].std(ddof=1)),
        float(np.sqrt(np.sum(dtheta**2) / (len(p) - 1))),
    )


def measured_change(
    start: tuple[float, float, float],
    end: tuple[float, float, float],
    start_cov: FloatArray,
    end_cov: FloatArray,
    net_turn_rad: float,
    winding_rad: float,
) -> tuple[FloatArray, FloatArray]:
    """The pose change from the ``start`` rest pose to the ``end`` one (each
    x m, y m, theta rad in one world frame) in the start frame, its heading
    taken within pi of the encoder's ``net_turn_rad`` and minus
    ``winding_rad``; and its 3x3 covariance from the rest poses' covariances
    (world axes)."""
    dx, dy, dtheta = relative_pose(start, end)
    heading = angle_near(dtheta, net_turn_rad)
    change = np.array([dx, dy, heading - winding_rad], dtype=np.float64)
    by_start, by_end = relative_pose_jacobians(start, end)
    cov = by_start @ np.asarray(start_cov) @ by_start.T + by_end @ np.asarray(end_cov) @ by_end.T
    return change, 0.5 * (cov + cov.T)
