"""A recording cut into trials: at rest or by a given cut
(:func:`~odohil.session.trials.logs.recording.trials_of`), or, with
``--window-m``, into consecutive windows of travelled wheel distance (a
continuous log: a robot driving around a motion-capture lab without rests).

Each window (odohil/science/distance_windows.py: cut by the odometry alone,
non-overlapping, the last partial window dropped) is a general-path trial:
its encoder path as driven (compressed, turns included as they come), and
the ground truth's pose change from the window's first sample to its last,
each pose with the covariance of the description's ``[measurement]
pose_sigma`` (required: a window's ends are single poses, not rests whose
scatter could stand in for it). A window is left out, and counted, when the
ground truth is missing (or not finite) at its first or last sample, or is
missing inside it for longer than ``--max-truth-gap`` (0.5 s, the bound of
rest-cut trials: shorter drop-outs cost the trial nothing, since only its end
poses are measured, while a longer one may hide a lost or swapped rigid
body). With ``--window-m`` the rests and a ``trial`` column are not used.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from odohil import units
from odohil.errors import ParameterError, RecordingError
from odohil.science.distance_windows import distance_windows
from odohil.science.path_trials import PathTrial
from odohil.science.robot_description import RobotDescription
from odohil.session.trials.logs.recording import ImportOptions, Recording, path_trial, trials_of

WINDOW_FAMILY = "window"
"""The path family of every window, its direction ``mixed``: the windows are
draws of one way of driving, not designs, so the model checks and the
minimum of trials a family and direction take them as one group (the
trial-order check still runs; ``--family window`` selects them)."""

WINDOW_M_HELP = (
    "Continuous logs (no rests): cut the motion into consecutive windows of this travelled "
    "wheel distance, m, each a trial from the ground truth at its first sample to its last; "
    "a window with a gap in the ground truth is left out and counted, the last partial one "
    "dropped (docs/recording.md). Needs \\[measurement] pose_sigma."
)
"""``--window-m`` of every command that reads a recording."""

__all__ = [
    "WINDOW_FAMILY",
    "WINDOW_M_HELP",
    "Cut",
    "WindowCount",
    "cut_of",
    "joined",
    "next_number",
]


WINDOWS_NAMED = 5
"""Most windows left out that :meth:`WindowCount.lines` names one by one."""


@dataclass(frozen=True)
class WindowCount:
    """How a recording's windows went (``--window-m``).

    Attributes:
        window_m: the window length, m of travelled wheel distance.
        used: windows made trials.
        left_out: where and why, one per window left out for a gap in the
            ground truth.
        partial: recordings whose last partial window was dropped.
        dropped_m: the distance of the partial windows dropped, m.
    """

    window_m: float
    used: int
    left_out: tuple[str, ...] = ()
    partial: int = 0
    dropped_m: float = 0.0

    def to_json_dict(self) -> dict[str, object]:
        """``window_m``, ``windows`` (used), ``left_out_truth_gap`` (a count),
        ``left_out`` (why each), ``partial_dropped`` and ``partial_dropped_m``."""
        return {
            "window_m": self.window_m,
            "windows": self.used,
            "left_out_truth_gap": len(self.left_out),
            "left_out": list(self.left_out),
            "partial_dropped": self.partial,
            "partial_dropped_m": self.dropped_m,
        }

    def summary(self) -> str:
        """``windows of 2 m travelled (--window-m): 29 trials, 1 left out for
        a gap in the ground truth, 1 partial window dropped (1.08 m)``."""
        partial = (
            f", {units.plural(self.partial, 'partial window')} dropped ({self.dropped_m:.3g} m)"
            if self.partial
            else ""
        )
        return (
            f"windows of {self.window_m:g} m travelled (--window-m): "
            f"{units.plural(self.used, 'trial')}, {len(self.left_out)} left out for a gap in "
            f"the ground truth{partial}"
        )

    def named(self) -> list[str]:
        """``left out: WHERE AND WHY`` for the first :data:`WINDOWS_NAMED`
        windows left out, then ``and N more``."""
        named = [f"left out: {why}" for why in self.left_out[:WINDOWS_NAMED]]
        if len(self.left_out) > WINDOWS_NAMED:
            named.append(f"and {len(self.left_out) - WINDOWS_NAMED} more")
        return named

    def lines(self) -> list[str]:
        """:meth:`summary`, then :meth:`named` as a list under it: the text
        under an estimate and import's."""
        return [self.summary(), *(f"  - {line}" for line in self.named())]


@dataclass(frozen=True)
class Cut:
    """The trials of a recording, and how its windows went (None unless
    cut by ``--window-m``)."""

    trials: tuple[PathTrial, ...]
    windows: WindowCount | None = None


def joined(cuts: Sequence[Cut]) -> Cut:
    """The cuts of several recordings as one (trials in order, counts summed)."""
    trials = tuple(trial for cut in cuts for trial in cut.trials)
    counts = [cut.windows for cut in cuts if cut.windows is not None]
    if not counts:
        return Cut(trials)
    return Cut(
        trials,
        WindowCount(
            counts[0].window_m,
            sum(c.used for c in counts),
            tuple(why for c in counts for why in c.left_out),
            sum(c.partial for c in counts),
            sum(c.dropped_m for c in counts),
        ),
    )


def next_number(cuts: Sequence[Cut]) -> int:
    """The number of the next trial after those of ``cuts`` (from 1)."""
    return 1 + sum(len(cut.trials) for cut in cuts)


def cut_of(
    rec: Recording, description: RobotDescription, options: ImportOptions, first_number: int = 1
) -> Cut:
    """The trials of a recording, numbered from ``first_number``: windows of
    ``options.window_m`` (module docstring), else at rest or by the given cut.

    Raises:
        RecordingError: no trial (the message says why: shorter than one
            window, every window left out, never at rest, ...).
        ParameterError: ``--window-m`` with a description without
            ``[measurement] pose_sigma``.
    """
    if options.window_m is None:
        return Cut(tuple(trials_of(rec, description, options, first_number)))
    if description.pose_sigma is None:
        raise ParameterError(
            "--window-m: the robot description gives no [measurement] pose_sigma; a window "
            "starts and ends at single ground-truth poses, whose accuracy it must state "
            "(docs/motion-capture.md#pose_sigma-and-the-covariance)"
        )
    windows = distance_windows(rec.odometry, options.window_m)
    if not windows.spans:
        raise RecordingError(
            f"{rec.source}: {rec.odometry_field}: the odometry travels "
            f"{windows.travelled_m:.3f} m in all, shorter than one window of "
            f"--window-m {options.window_m:g} m; no trial"
        )
    pose_cov = np.diag(np.square(np.array(description.pose_sigma, dtype=np.float64)))
    trials: list[PathTrial] = []
    left_out: list[str] = []
    for first, last in windows.spans:
        gap = _truth_gap(rec, first, last, options.max_truth_gap_s)
        if gap:
            left_out.append(f"{rec.at(first)}-{int(rec.where[last])}: {gap}")
            continue
        trials.append(
            _window_trial(rec, first, last, pose_cov, options, first_number + len(trials))
        )
    if not trials:
        raise RecordingError(
            f"{rec.source}: {rec.truth_field}: every window of --window-m "
            f"{options.window_m:g} m ({len(left_out)}) has a gap in the ground truth; no trial "
            f"(the first: {left_out[0]})"
        )
    partial = int(windows.dropped_m > 0)
    count = WindowCount(options.window_m, len(trials), tuple(left_out), partial, windows.dropped_m)
    return Cut(tuple(trials), count)


def _truth_gap(rec: Recording, first: int, last: int, max_gap_s: float) -> str:
    """Why the ground truth of samples ``first..last`` cannot measure a
    window ("" when it can)."""
    present = np.all(np.isfinite(rec.truth[first : last + 1]), axis=1)
    for end, index in (("first", 0), ("last", -1)):
        if not present[index]:
            return f"no ground truth at the window's {end} sample ({rec.truth_field})"
    times = rec.t_s[first : last + 1][present]
    gaps = np.diff(times)
    worst = int(np.argmax(gaps)) if len(gaps) else 0
    if len(gaps) and gaps[worst] > max_gap_s:
        return (
            f"a gap in the ground truth of {gaps[worst]:.3g} s from {float(times[worst]):.3f} s "
            f"(at most {max_gap_s:g} s, --max-truth-gap)"
        )
    return ""


def _window_trial(
    rec: Recording,
    first: int,
    last: int,
    pose_cov: np.ndarray,
    options: ImportOptions,
    number: int,
) -> PathTrial:
    start, end = rec.truth[first], rec.truth[last]
    return path_trial(
        rec, first, last,
        ((float(start[0]), float(start[1]), float(start[2])), pose_cov),
        ((float(end[0]), float(end[1]), float(end[2])), pose_cov),
        options, number, "window", (WINDOW_FAMILY, "mixed"),
    )  # fmt: skip
