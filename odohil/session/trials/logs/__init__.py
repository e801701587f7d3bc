"""Trials from recorded logs of any path: one module per log format.

The API (stable; the general-path estimator and ``odohil import`` call it)::

    read_recording(paths, description, options) -> list[PathTrial]
    read_cut(paths, description, options) -> Cut  # the trials, and how the windows went

reads the files ``paths`` in the format ``options.format`` (None: guessed by
:func:`guess_format`), cuts them into trials (at rest, by a given cut, or
with ``options.window_m`` into windows of travelled distance:
odohil/session/trials/logs/windows.py) and returns one
:class:`~odohil.science.path_trials.PathTrial` per trial, numbered from 1 in
file order. ``description`` is the robot description: its
``[robot]`` geometry turns wheel counts into odometry (CSV logs with
``ticks_left,ticks_right``) and its ``[measurement] pose_sigma``, when given,
is the ground truth's accuracy (odohil/session/trials/logs/recording.py).

Per format (each ``(paths, description, options) -> Cut``):

- ``csv``: :func:`odohil.session.trials.logs.csv_log.read_csv_logs`, odohil's own log;
- ``tum``: :func:`odohil.session.trials.logs.tum.read_tum_pairs`, TUM trajectory
  files in pairs (odometry, ground truth);
- ``rosbag``: :func:`odohil.session.trials.logs.rosbag.read_bags`, ROS 2 bags
  (sqlite3 or MCAP) through the ``rosbags`` library;
- ``optiodom``: :func:`odohil.session.trials.logs.optiodom.read_optiodom`, the
  optiodom data set's run files.

Errors are :class:`~odohil.errors.RecordingError` (a MeasurementError) naming
the file, the line or message, and the field. docs/recording.md tells how to
record a log odohil can use.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Sequence
from pathlib import Path

from odohil.errors import RecordingError
from odohil.science.path_trials import PathTrial
from odohil.science.robot_description import RobotDescription
from odohil.session.trials.logs.recording import ImportOptions
from odohil.session.trials.logs.windows import WINDOW_M_HELP, Cut, WindowCount

Reader = Callable[[list[Path], RobotDescription, ImportOptions], Cut]

READERS: dict[str, str] = {
    "csv": "odohil.session.trials.logs.csv_log:read_csv_logs",
    "tum": "odohil.session.trials.logs.tum:read_tum_pairs",
    "rosbag": "odohil.session.trials.logs.rosbag:read_bags",
    "optiodom": "odohil.session.trials.logs.optiodom:read_optiodom",
}
"""Each format's reader, by name (imported when used: ``rosbags`` only for bags)."""
FORMATS: tuple[str, ...] = tuple(READERS)

__all__ = [
    "FORMATS",
    "READERS",
    "WINDOW_M_HELP",
    "Cut",
    "ImportOptions",
    "WindowCount",
    "guess_format",
    "read_cut",
    "read_recording",
    "reader",
]


def reader(name: str) -> Reader:
    """The reader of format ``name``.

    Raises:
        RecordingError: an unknown format (the message lists the known ones).
    """
    target = READERS.get(name)
    if target is None:
        raise RecordingError(f"unknown log format {name!r}; known: {', '.join(FORMATS)}")
    module, function = target.split(":")
    found: Reader = getattr(importlib.import_module(module), function)
    return found


def guess_format(paths: Sequence[Path]) -> str:
    """The format the paths look like: ``rosbag`` for ``.mcap``/``.db3`` files
    or folders holding a ``metadata.yaml``; ``optiodom`` for run files and
    folders holding ``*_metadata.csv``; ``tum`` for ``.tum``/``.txt`` files;
    else ``csv``."""
    path = paths[0] if paths else Path()
    if path.suffix in (".mcap", ".db3") or (path / "metadata.yaml").is_file():
        return "rosbag"
    if path.is_dir() or "_run-" in path.name:
        return "optiodom"
    if path.suffix in (".tum", ".txt"):
        return "tum"
    return "csv"


def read_recording(
    paths: Sequence[str | Path], description: RobotDescription, options: ImportOptions
) -> list[PathTrial]:
    """The trials of a recording (module docstring; :func:`read_cut`'s trials).

    Raises:
        RecordingError: unreadable or unusable files (the message names the
            file, the line or message, and the field), or no trial at all.
        ParameterError: ``--window-m`` without ``[measurement] pose_sigma``.
    """
    return list(read_cut(paths, description, options).trials)


def read_cut(
    paths: Sequence[str | Path], description: RobotDescription, options: ImportOptions
) -> Cut:
    """The trials of a recording and, with ``options.window_m``, how its
    windows went (:class:`WindowCount`).

    Raises:
        as :func:`read_recording`.
    """
    files = [Path(path) for path in paths]
    if not files:
        raise RecordingError("no log file given")
    name = options.format or guess_format(files)
    cut = reader(name)(files, description, options)
    if not cut.trials:
        raise RecordingError(f"no trial in {', '.join(map(str, files))}")
    return cut
