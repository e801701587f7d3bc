"""A continuous recording cut into windows of travelled wheel distance.

A robot driving around a motion-capture lab without ever resting gives no
rest to cut a trial at. Under the model (Martinelli's eqs. 1-5) the errors of
disjoint stretches of motion are independent, each with variance rates per
metre travelled (K_theta, K_rho), so consecutive stretches of equal
travelled distance are independent trials of a general path, each from the
ground truth at its first sample to the ground truth at its last
(docs/recording.md, "Continuous logs: --window-m").

:func:`distance_windows` cuts by the odometry alone (never by the ground
truth, so that which windows exist does not depend on what the capture saw):
the distance travelled is the sum of ``|ds|``, each sample step's length in
the odometry's plane (the chord of the step's arc, shorter than the arc by
``dtheta^2 / 24`` of it: under 1e-5 at the 0.015 rad a 100 Hz sample turns at
1.5 rad/s). In-place turns travel no distance and fall into whichever window
they come in. A window starts at a sample and ends at the first sample at
which it has travelled at least ``window_m``; the next window starts at the
sample after, so that no two windows share a sample (and with it the noise of
one ground-truth pose: adjacent windows' measured pose changes would otherwise
be correlated through it). The stretch between a window's last sample and
the next one's first (one sample interval) belongs to neither. What is left
after the last whole window is dropped.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from odohil.errors import ParameterError
from odohil.science.paths import FloatArray


@dataclass(frozen=True)
class DistanceWindows:
    """The windows of a recording.

    Attributes:
        spans: (first, last) sample index of each whole window, in order.
        travelled_m: the distance travelled over the whole recording, m.
        dropped_m: the distance travelled after the last whole window
            (the partial window dropped), m.
    """

    spans: tuple[tuple[int, int], ...]
    travelled_m: float
    dropped_m: float


def travelled(odometry: FloatArray) -> FloatArray:
    """(n,) the distance travelled from the first odometry sample to each, m:
    the cumulative sum of each step's length ``|ds|`` (module docstring)."""
    poses = np.asarray(odometry, dtype=np.float64)
    steps = np.hypot(np.diff(poses[:, 0]), np.diff(poses[:, 1]))
    return np.concatenate([[0.0], np.cumsum(steps)])


def check_window(window_m: float, option: str = "window_m") -> float:
    """``window_m`` if it is a finite number of metres above 0.

    Raises:
        ParameterError: naming ``option`` and the range accepted.
    """
    if not (isinstance(window_m, int | float) and math.isfinite(window_m) and window_m > 0):
        raise ParameterError(
            f"{option} must be a finite number of metres above 0 (0 < {option} < inf), "
            f"got {window_m!r}"
        )
    return float(window_m)


def distance_windows(odometry: FloatArray, window_m: float) -> DistanceWindows:
    """The consecutive, non-overlapping windows of ``window_m`` metres
    travelled of the odometry poses ``odometry`` ((n, 3): x m, y m, theta
    rad), by the module docstring's rule.

    Raises:
        ParameterError: ``window_m`` not a finite number above 0.
    """
    window_m = check_window(window_m)
    distance = travelled(odometry)
    spans: list[tuple[int, int]] = []
    first = 0
    while first < len(distance):
        last = int(np.searchsorted(distance, distance[first] + window_m, side="left"))
        if last >= len(distance):
            break
        spans.append((first, last))
        first = last + 1
    total = float(distance[-1]) if len(distance) else 0.0
    dropped = total - float(distance[spans[-1][1]]) if spans else total
    return DistanceWindows(tuple(spans), total, dropped)
