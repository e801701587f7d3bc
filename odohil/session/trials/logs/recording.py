"""A recording as every log format reads it, and how it is cut into trials.

Each format's reader (one module per format in this package) turns its files
into :class:`Recording` values: times, odometry poses and ground-truth poses
on one clock, sample by sample, with where each sample came from (a line or a
message) for error messages, and optionally a given cut (a ``trial`` column,
or one file per trial). :func:`trials_of` then cuts a recording into
:class:`~odohil.science.path_trials.PathTrial` values with the science layer's
pure functions (odohil/science/rest_cutting.py, odohil/science/odometry_paths.py).

Covariance of a rest pose (decided here, docs/recording.md): the robot
description's ``[measurement] pose_sigma`` when it gives one (the capture
system's accuracy as its owner states it: calibration and marker errors do not
average out over a rest); otherwise the rest's own scatter, as the standard
error of its mean (sample variance / number of samples, the jitter taken as
white), each standard deviation at least :data:`SCATTER_FLOOR`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from odohil.errors import MeasurementError, ParameterError, RecordingError
from odohil.science.distance_windows import check_window
from odohil.science.odometry_paths import CompressionBounds, compress_odometry, path_family
from odohil.science.path_trials import Direction, PathTrial
from odohil.science.paths import FloatArray
from odohil.science.rest_cutting import (
    EDGE_MOVE_M,
    EDGE_TURN_RAD,
    MIN_EDGE_REST_S,
    MIN_REST_S,
    edge_rests,
    mean_pose,
    measured_change,
    pose_scatter,
    rest_windows,
    still_mask,
)
from odohil.science.robot_description import RobotDescription
from odohil.session.progress import Progress, Tell, stage
from odohil.units import wrap_angle

IntArray = npt.NDArray[np.int64]

MAX_TRUTH_GAP_S = 0.5
"""Longest time without a ground-truth pose inside a trial, s: the rests need
several poses to average, and a heading sampled this often is continuous
for a robot turning below 2 pi rad/s."""
DEFAULT_MAX_TIME_DIFF_S = 0.01
"""Largest difference of associated odometry and ground-truth stamps, s
(evo's ``--t_max_diff`` default)."""
SCATTER_FLOOR = (1e-5, 1e-5, 1e-4)
"""Smallest standard deviation of a rest pose from its scatter: x m, y m, theta rad."""

OPTION_NAMES = {
    "max_time_diff_s": "--max-time-diff",
    "time_offset_s": "--time-offset",
    "min_rest_s": "--min-rest",
    "min_edge_rest_s": "--min-edge-rest",
    "max_truth_gap_s": "--max-truth-gap",
}
"""The command-line option of each timing field (``odohil import``), for messages."""


@dataclass(frozen=True)
class ImportOptions:
    """How a recording is read and cut (the options of ``odohil import``).

    Attributes:
        format: ``csv``, ``tum``, ``rosbag`` or ``optiodom``; None guesses
            from the paths (:func:`odohil.session.trials.logs.guess_format`).
        odom_topic: the odometry topic of a bag (nav_msgs/msg/Odometry).
        truth_topic: the ground-truth topic of a bag
            (geometry_msgs/msg/PoseStamped or nav_msgs/msg/Odometry).
        max_time_diff_s: largest stamp difference of an associated
            odometry and ground-truth pair (TUM, bags), s.
        time_offset_s: added to the ground truth's stamps before associating, s.
        min_rest_s: shortest rest that separates two trials, s.
        min_edge_rest_s: shortest still stretch at either end of a trial whose
            cut is given (a ``trial`` column, one file per trial) that is
            averaged as its rest, s; a trial without one (it moves at once)
            starts at its first sample (ends at its last). 0: every still
            stretch is averaged, however short.
        max_truth_gap_s: longest time without a ground-truth pose in a trial, s.
        window_m: cut into windows of this travelled wheel distance, m,
            in place of rests and given cuts (a continuous log:
            odohil/session/trials/logs/windows.py); None: not.
        bounds: how odometry is compressed into legs and turns.
        progress: told how far reading and cutting have gone
            (odohil/session/progress.py); None: nobody. Not compared.
    """

    format: str | None = None
    odom_topic: str = "/odom"
    truth_topic: str = "/ground_truth"
    max_time_diff_s: float = DEFAULT_MAX_TIME_DIFF_S
    time_offset_s: float = 0.0
    min_rest_s: float = MIN_REST_S
    min_edge_rest_s: float = MIN_EDGE_REST_S
    max_truth_gap_s: float = MAX_TRUTH_GAP_S
    window_m: float | None = None
    bounds: CompressionBounds = field(default_factory=CompressionBounds)
    progress: Progress | None = field(default=None, compare=False, repr=False)

    def __post_init__(self) -> None:
        for name, option in OPTION_NAMES.items():
            value = getattr(self, name)
            if name == "time_offset_s":
                if not math.isfinite(value):
                    raise ParameterError(
                        f"{option} must be a finite number of seconds, got {value!r}"
                    )
            elif name == "min_edge_rest_s":
                if not (math.isfinite(value) and value >= 0):
                    raise ParameterError(
                        f"{option} must be zero or a positive number of seconds, got {value!r}"
                    )
            elif not (math.isfinite(value) and value > 0):
                raise ParameterError(
                    f"{option} must be a positive number of seconds, got {value!r}"
                )
        if self.window_m is not None:
            check_window(self.window_m, "--window-m")


@dataclass(frozen=True)
class Recording:
    """Odometry and ground truth on one clock, sample by sample.

    Attributes:
        source: the file (or bag) name, for messages and the trials' source.
        t_s: (n,) sample times, strictly increasing, s.
        odometry: (n, 3) odometry poses (x m, y m, theta rad) in the
            odometry's frame; headings may be wrapped.
        truth: (n, 3) ground-truth poses in any world frame; NaN where missing.
        where: (n,) the line (or message) number of each sample.
        unit: what :attr:`where` counts (``line``, ``odometry message``).
        trial: (n,) the given trial label of each sample ("" between trials),
            or None to cut at rest.
        odometry_field, truth_field: how messages name the odometry and the
            ground truth (the format's own names).
    """

    source: str
    t_s: FloatArray
    odometry: FloatArray
    truth: FloatArray
    where: IntArray
    unit: str = "line"
    trial: tuple[str, ...] | None = None
    odometry_field: str = "odo_x_m/odo_y_m/odo_theta_rad"
    truth_field: str = "true_x_m/true_y_m/true_theta_rad"

    def at(self, index: int) -> str:
        """``SOURCE line N`` of sample ``index``."""
        return f"{self.source} {self.unit} {int(self.where[index])}"


def check_increasing(t_s: FloatArray, where: IntArray, source: str, field: str, unit: str) -> None:
    """RecordingError at the first sample whose time does not increase."""
    t = np.asarray(t_s, dtype=np.float64)
    if len(t) < 2:
        raise RecordingError(f"{source}: {field}: at least 2 samples are needed, got {len(t)}")
    bad = np.flatnonzero(np.diff(t) <= 0)
    if len(bad):
        i = int(bad[0]) + 1
        raise RecordingError(
            f"{source} {unit} {int(where[i])}: {field} must increase, got {float(t[i])!r} "
            f"after {float(t[i - 1])!r} ({unit} {int(where[i - 1])})"
        )


def _rest_cov(poses: FloatArray, description: RobotDescription, other: FloatArray) -> FloatArray:
    """The covariance of a rest's mean pose (module docstring). A rest of one
    sample (a trial that moves at once) has no scatter of its own: the other
    rest's scatter per sample stands for the capture's jitter, if it has one."""
    if description.pose_sigma is not None:
        return np.diag(np.square(np.array(description.pose_sigma, dtype=np.float64)))
    spread = poses if len(poses) > 1 or len(other) < 2 else other
    scatter = np.array(pose_scatter(spread)) / math.sqrt(len(poses))
    return np.diag(np.square(np.maximum(scatter, np.array(SCATTER_FLOOR))))


def _truth_in(rec: Recording, first: int, last: int, what: str) -> FloatArray:
    poses = rec.truth[first : last + 1]
    poses = poses[np.all(np.isfinite(poses), axis=1)]
    if len(poses) == 0:
        raise RecordingError(
            f"{rec.at(first)}-{int(rec.where[last])}: {rec.truth_field}: "
            f"no ground truth during the rest at the {what} of a trial"
        )
    return poses


def _check_gaps(rec: Recording, first: int, last: int, max_gap_s: float) -> None:
    present = np.flatnonzero(np.all(np.isfinite(rec.truth[first : last + 1]), axis=1)) + first
    if len(present) == 0:
        raise RecordingError(f"{rec.at(first)}: {rec.truth_field}: no ground truth in the trial")
    times = rec.t_s[present]
    edges = np.concatenate([[rec.t_s[first]], times, [rec.t_s[last]]])
    gaps = np.diff(edges)
    worst = int(np.argmax(gaps))
    if gaps[worst] > max_gap_s:
        before = first if worst == 0 else int(present[worst - 1])
        after = last if worst == len(present) else int(present[worst])
        raise RecordingError(
            f"{rec.at(before)}: {rec.truth_field}: a gap in the ground truth "
            f"of {gaps[worst]:.3g} s (to {rec.unit} {int(rec.where[after])}); "
            f"at most {max_gap_s:g} s allowed (--max-truth-gap)"
        )


def _trial(
    rec: Recording,
    start: tuple[int, int],
    end: tuple[int, int],
    description: RobotDescription,
    options: ImportOptions,
    number: int,
) -> PathTrial:
    _check_gaps(rec, start[0], end[1], options.max_truth_gap_s)
    # The truth poses and the path cover the same time: a rest's odometry may
    # creep within the edge tolerances (a gear's backlash as the wheels start;
    # 1-2 mm on the optiodom robot), so only its part where the odometry holds
    # the edge value exactly is averaged, and the path runs from there.
    start = (start[0], _held_until(rec.odometry, start[0], start[1]))
    end = (_held_from(rec.odometry, end[0], end[1]), end[1])
    first, last = start[1], end[0]
    start_poses = _truth_in(rec, start[0], start[1], "start")
    end_poses = _truth_in(rec, end[0], end[1], "end")
    return path_trial(
        rec, first, last,
        (mean_pose(start_poses), _rest_cov(start_poses, description, end_poses)),
        (mean_pose(end_poses), _rest_cov(end_poses, description, start_poses)),
        options, number, "trial",
    )  # fmt: skip


def path_trial(
    rec: Recording,
    first: int,
    last: int,
    start: tuple[tuple[float, float, float], FloatArray],
    end: tuple[tuple[float, float, float], FloatArray],
    options: ImportOptions,
    number: int,
    kind: str,
    family: tuple[str, Direction] | None = None,
) -> PathTrial:
    """Trial ``number`` of samples ``first``..``last``: the odometry between as
    its encoder path, the change from the truth pose ``start`` to ``end``
    ((x m, y m, theta rad), 3x3 covariance each) as its measurement; named
    ``kind`` ("trial", "window") in messages; (family, direction) as
    ``path_family`` tells them unless given.

    Raises:
        RecordingError: the odometry between is no path (the sample named).
    """
    try:
        path = compress_odometry(
            rec.odometry[first : last + 1], options.bounds, name=f"{rec.source} {kind} {number}"
        )
    except (MeasurementError, ParameterError) as exc:
        raise RecordingError(f"{rec.at(first)}: {rec.odometry_field}: {exc}") from None
    change, cov = measured_change(
        start[0], end[0], start[1], end[1], path.net_turn_rad, path.winding_rad
    )
    named, direction = path_family(path) if family is None else family
    return PathTrial(
        path=path,
        pose_change=change,
        measurement_cov=cov,
        source=rec.source,
        span_s=(float(rec.t_s[first]), float(rec.t_s[last])),
        trial=number,
        family=named,
        direction=direction,
    )


_HELD_M = 1e-9
_HELD_RAD = 1e-9
"""How close two odometry poses are to count as the same (m, rad)."""


def _held(odometry: FloatArray, reference: int, index: int) -> bool:
    d = odometry[index] - odometry[reference]
    return bool(
        math.hypot(float(d[0]), float(d[1])) <= _HELD_M
        and abs(wrap_angle(float(d[2]))) <= _HELD_RAD
    )


def _held_until(odometry: FloatArray, first: int, last: int) -> int:
    """The last index of ``first..last`` up to which the odometry holds its
    value at ``first`` (a rest's part before the odometry creeps)."""
    index = first
    while index < last and _held(odometry, first, index + 1):
        index += 1
    return index


def _held_from(odometry: FloatArray, first: int, last: int) -> int:
    """The first index of ``first..last`` from which the odometry holds its
    value at ``last``."""
    index = last
    while index > first and _held(odometry, last, index - 1):
        index -= 1
    return index


def _given_cuts(rec: Recording) -> list[tuple[str, int, int]]:
    """(label, first, last) of each run of one trial label."""
    assert rec.trial is not None
    runs: list[tuple[str, int, int]] = []
    seen: dict[str, int] = {}
    for index, label in enumerate(rec.trial):
        if runs and runs[-1][0] == label:
            runs[-1] = (label, runs[-1][1], index)
            continue
        if label and label in seen:
            raise RecordingError(
                f"{rec.at(index)}: trial: trial {label!r} appears again after other rows "
                f"(it started at {rec.unit} {seen[label]}); a trial's rows must be consecutive"
            )
        if label:
            seen[label] = int(rec.where[index])
        runs.append((label, index, index))
    return [run for run in runs if run[0]]


def trials_of(
    rec: Recording, description: RobotDescription, options: ImportOptions, first_number: int = 1
) -> list[PathTrial]:
    """The trials of a recording, numbered from ``first_number`` (module docstring).

    Raises:
        RecordingError: the robot is never at rest where a trial must start or
            end, the ground truth has a gap, or the recording holds no trial;
            the message names the file, the line and the field.
    """
    with stage(options.progress, CUTTING) as tell:
        return _trials_of(rec, description, options, first_number, tell)


CUTTING = "cutting trials"
"""The progress stage of :func:`trials_of` (counts: trials)."""


def _trials_of(
    rec: Recording,
    description: RobotDescription,
    options: ImportOptions,
    first_number: int,
    tell: Tell,
) -> list[PathTrial]:
    trials: list[PathTrial] = []
    if rec.trial is not None:
        cuts = _given_cuts(rec)
        if not cuts:
            raise RecordingError(f"{rec.source}: trial: no row names a trial; no trial in the log")
        for done, (label, first, last) in enumerate(cuts):
            tell(done, len(cuts))
            if not _odometry_moved(rec, first, last):
                raise RecordingError(
                    f"{rec.at(first)}-{int(rec.where[last])}: {rec.odometry_field}: the odometry "
                    f"of trial {label!r} never moves; no trial"
                )
            start, end = edge_rests(
                rec.t_s[first : last + 1], rec.odometry[first : last + 1], options.min_edge_rest_s
            )
            # no rest at an end (the trial moves at once, or ends moving): the
            # end's pose is its first (last) sample alone
            start = start or (0, 0)
            end = end or (last - first, last - first)
            trials.append(
                _trial(
                    rec,
                    (first + start[0], first + start[1]),
                    (first + end[0], first + end[1]),
                    description,
                    options,
                    first_number + len(trials),
                )
            )
        return trials
    still = still_mask(rec.t_s, rec.odometry) & still_mask(rec.t_s, rec.truth)
    windows = rest_windows(rec.t_s, still, options.min_rest_s)
    if not windows:
        raise RecordingError(
            f"{rec.source}: {rec.odometry_field}, {rec.truth_field}: the robot is never at rest "
            f"(odometry and ground "
            f"truth both still for {options.min_rest_s:g} s; --min-rest), so no trial can be cut"
        )
    start = windows[0]
    for end in windows[1:]:
        if _odometry_moved(rec, start[1], end[0]):
            trials.append(_trial(rec, start, end, description, options, first_number + len(trials)))
        # else only the ground truth moved between the rests (a capture glitch, a
        # robot pushed): no trial; the later rest is where the next one starts
        start = end
    if not trials:
        first, last = windows[0]
        raise RecordingError(
            f"{rec.at(first)}-{int(rec.where[last])}: no trial in the log: the odometry "
            "never moves between two rests (a trial is the motion between two rests)"
        )
    return trials


def _odometry_moved(rec: Recording, first: int, last: int) -> bool:
    """Whether the odometry leaves the pose it had at ``first`` before ``last``
    by more than the edge tolerances (odohil/science/rest_cutting.py)."""
    poses = rec.odometry[first : last + 1]
    d_xy = np.hypot(poses[:, 0] - poses[0, 0], poses[:, 1] - poses[0, 1])
    d_theta = np.abs(np.unwrap(poses[:, 2]) - poses[0, 2])
    return bool(np.any(d_xy > EDGE_MOVE_M) or np.any(d_theta > EDGE_TURN_RAD))


def associate(
    source: str,
    odometry_t_s: FloatArray,
    odometry: FloatArray,
    odometry_where: IntArray,
    truth_t_s: FloatArray,
    truth: FloatArray,
    options: ImportOptions,
    *,
    unit: str,
    odometry_field: str,
    truth_field: str,
) -> Recording:
    """Odometry and ground truth on two clocks made one recording, the way
    the evo tool associates trajectories: each odometry stamp takes the
    ground-truth pose of the nearest stamp (after adding
    ``options.time_offset_s`` to the ground truth's), if it lies within
    ``options.max_time_diff_s``; odometry samples without one are left out
    (odometry poses are cumulative, nothing is lost; a stretch without ground
    truth shows as a time gap between the samples kept, which
    :func:`trials_of` refuses when it is longer than ``max_truth_gap_s``).

    Raises:
        RecordingError: the two clocks do not overlap (the message gives both
            spans), or no stamps are close enough to associate.
    """
    t_odo = np.asarray(odometry_t_s, dtype=np.float64)
    t_truth = np.asarray(truth_t_s, dtype=np.float64) + options.time_offset_s
    slack = options.max_time_diff_s
    inside = (t_odo >= t_truth[0] - slack) & (t_odo <= t_truth[-1] + slack)
    if inside.sum() < 2:
        raise RecordingError(
            f"{source}: the clocks do not overlap: odometry {t_odo[0]:.6f}-{t_odo[-1]:.6f} s, "
            f"ground truth {t_truth[0]:.6f}-{t_truth[-1]:.6f} s (after --time-offset "
            f"{options.time_offset_s:g} s); check the stamps or give --time-offset"
        )
    t = t_odo[inside]
    right = np.clip(np.searchsorted(t_truth, t), 1, len(t_truth) - 1)
    left = right - 1
    nearest = np.where(np.abs(t_truth[left] - t) <= np.abs(t_truth[right] - t), left, right)
    if len(t_truth) == 1:
        nearest = np.zeros(len(t), dtype=np.int64)
    matched = np.abs(t_truth[nearest] - t) <= slack
    if matched.sum() < 2:
        raise RecordingError(
            f"{source}: no odometry stamp lies within --max-time-diff "
            f"{options.max_time_diff_s:g} s of a ground-truth stamp"
        )
    return Recording(
        source=source,
        t_s=t[matched],
        odometry=np.asarray(odometry, dtype=np.float64)[inside][matched],
        truth=np.asarray(truth, dtype=np.float64)[nearest[matched]],
        where=np.asarray(odometry_where, dtype=np.int64)[inside][matched],
        unit=unit,
        odometry_field=odometry_field,
        truth_field=truth_field,
    )
