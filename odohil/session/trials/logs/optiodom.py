"""The optiodom data set's run files (Sousa et al. 2022; ../shared/data/optiodom-june).

Layout: ``<kind>/<session>/<session>_run-NN.csv`` beside
``<session>_metadata.csv``. A run file has no header and one row per 50 ms
cycle: time since the run's start (s), ground-truth x, y (m) and heading
(rad) in the run's start frame, then the right and the left wheel's encoder
counts *in that cycle* (increments). Each run is one trial; the robot stands
still at its start and end in the June sessions (the rests are found from the
odometry, odohil/science/rest_cutting.py); a run that moves at once starts at
its first sample (and one that ends moving ends at its last).

Geometry: the raw counts do not depend on the nominal constants each session
was configured with (some were deliberately wrong: ``Li`` 0.205 m, ``Di``
0.085 m), so every run is read with one nominal geometry, the data set's robot
(:func:`optiodom_geometry`: odohil/robots/datasets/optiodom.toml, from its
README), and the pooled trials share it.
The metadata is read to check the run count ``N`` and the encoder
(``encRes`` x ``ngear``) against the files.

A path may be a run file, a session folder, or any folder above them (every
``*_metadata.csv`` below it, in name order).
"""

from __future__ import annotations

import functools
import math
import operator
import re
import tomllib
from dataclasses import replace
from importlib.resources import files
from pathlib import Path

import numpy as np

from odohil.errors import RecordingError
from odohil.science.diff_drive import DiffDriveGeometry
from odohil.science.odometry_paths import integrate_ticks
from odohil.science.paths import FloatArray
from odohil.science.robot_description import RobotDescription
from odohil.science.robot_facts import DRIVE_KEYS
from odohil.session.progress import stage
from odohil.session.trials.logs.files import finite_number, read_text
from odohil.session.trials.logs.recording import (
    ImportOptions,
    IntArray,
    Recording,
    check_increasing,
)
from odohil.session.trials.logs.windows import Cut, cut_of, joined, next_number

GEOMETRY_FILE = "datasets/optiodom.toml"
"""The data set's robot, in the ``odohil.robots`` package (data, not a built-in ``--robot``)."""


@functools.cache
def optiodom_geometry() -> DiffDriveGeometry:
    """The data set's nominal robot (its README): one geometry for all
    sessions, from :data:`GEOMETRY_FILE`'s ``[robot]`` table."""
    text = files("odohil.robots").joinpath(GEOMETRY_FILE).read_text(encoding="utf-8")
    table = tomllib.loads(text)["robot"]
    return DiffDriveGeometry(**{key: float(table[key]) for key in DRIVE_KEYS})


RUN_COLUMNS = ("t_s", "true_x_m", "true_y_m", "true_theta_rad", "right_counts", "left_counts")
"""What the six columns of a run file hold (the names messages use)."""
MAX_RUNS = 10_000
"""Most run files read in one import."""
_RUN_NAME = re.compile(r"^(?P<session>.+)_run-(?P<run>\d+)\.csv$")
_COUNTS_TOLERANCE = 1e-6
_COMMAS = operator.methodcaller("count", ",")


def _metadata(path: Path) -> dict[str, list[str]]:
    table: dict[str, list[str]] = {}
    for line in read_text(path).splitlines():
        fields = [field.strip() for field in line.split(",")]
        if fields and fields[0]:
            table[fields[0]] = [field for field in fields[1:] if field]
    return table


def _check_metadata(path: Path, runs: list[Path]) -> None:
    table = _metadata(path)

    def number(key: str) -> float:
        values = table.get(key)
        try:
            return float(values[0]) if values else math.nan
        except ValueError:
            return math.nan

    if table.get("type", [""])[0:1] != ["diff"]:
        raise RecordingError(f"{path}: type: a differential drive (diff) is expected")
    counts = number("encRes") * number("ngear")
    nominal = optiodom_geometry().counts_per_rev
    if abs(counts - nominal) > _COUNTS_TOLERANCE * counts:
        raise RecordingError(
            f"{path}: encRes x ngear: {counts:g} counts per wheel turn; the data set's "
            f"robot has {nominal:g}"
        )
    expected = number("N")
    if expected != len(runs):
        raise RecordingError(
            f"{path}: N: the metadata lists {expected:g} runs, the folder holds {len(runs)} "
            f"run files"
        )


def run_files(paths: list[Path]) -> list[Path]:
    """The run files the paths name (module docstring), in order, each
    session's metadata checked against its runs.

    Raises:
        RecordingError: a path that is neither a run file nor a folder with
            sessions, a session without metadata, metadata that disagree.
    """
    found: list[Path] = []
    for path in paths:
        if path.is_dir():
            metas = sorted(path.rglob("*_metadata.csv"))
            if not metas:
                raise RecordingError(f"{path}: no optiodom session (*_metadata.csv) below it")
            for meta in metas:
                session = meta.name.removesuffix("_metadata.csv")
                runs = sorted(meta.parent.glob(f"{session}_run-*.csv"))
                _check_metadata(meta, runs)
                found.extend(runs)
        else:
            match = _RUN_NAME.match(path.name)
            if match is None:
                raise RecordingError(
                    f"{path}: not an optiodom run file (<session>_run-NN.csv) or folder"
                )
            meta = path.parent / f"{match['session']}_metadata.csv"
            if not meta.is_file():
                raise RecordingError(f"{path}: its session's metadata {meta.name} is missing")
            found.append(path)
        if len(found) > MAX_RUNS:
            raise RecordingError(f"at most {MAX_RUNS} run files are read in one import")
    return found


def _parsed_rows(path: Path, text: str) -> tuple[FloatArray, IntArray]:
    """The rows of a run file's ``text`` (blank lines skipped) and their line
    numbers: every row parsed with one ``float`` per field over the whole file
    (:func:`_checked_rows`, row by row, when a row is not six finite numbers:
    it names the first bad line and field).

    Raises:
        RecordingError: see :func:`read_run`.
    """
    lines = text.splitlines()
    if all(map(str.strip, lines)):  # no blank line: the usual file
        kept, where = lines, np.arange(1, len(lines) + 1, dtype=np.int64)
    else:
        numbers = [number for number, line in enumerate(lines, start=1) if line.strip()]
        kept, where = [lines[number - 1] for number in numbers], np.array(numbers, dtype=np.int64)
    columns = len(RUN_COLUMNS)
    if kept and set(map(_COMMAS, kept)) == {columns - 1}:
        try:
            flat = np.fromiter(
                map(float, ",".join(kept).split(",")), np.float64, len(kept) * columns
            )
        except ValueError:
            pass  # a field that is not a number: the row by row reading names it
        else:
            if np.isfinite(flat).all():
                return flat.reshape(len(kept), columns), where
    return _checked_rows(path, lines)


def _checked_rows(path: Path, lines: list[str]) -> tuple[FloatArray, IntArray]:
    """:func:`_parsed_rows` row by row, each field checked (the first bad one raises)."""
    rows: list[list[float]] = []
    where: list[int] = []
    for number, line in enumerate(lines, start=1):
        if not line.strip():
            continue
        fields = line.split(",")
        if len(fields) != len(RUN_COLUMNS):
            raise RecordingError(
                f"{path} line {number}: {len(fields)} columns; a run row has "
                f"{len(RUN_COLUMNS)} ({', '.join(RUN_COLUMNS)})"
            )
        values = [
            finite_number(path, number, name, field)
            for name, field in zip(RUN_COLUMNS, fields, strict=True)
        ]
        rows.append(values)
        where.append(number)
    if not rows:
        raise RecordingError(f"{path}: empty run file; no trial")
    return np.array(rows, dtype=np.float64), np.array(where, dtype=np.int64)


def read_run(path: Path) -> Recording:
    """One run file as a recording with one given trial (the run).

    Raises:
        RecordingError: unreadable file, a row without six numbers (the
            message names the line and the column), time not increasing.
    """
    data, lines = _parsed_rows(path, read_text(path))
    rows = len(data)
    check_increasing(data[:, 0], lines, str(path), "t_s", "line")
    geometry = optiodom_geometry()
    per_count = geometry.metres_per_count
    odometry = integrate_ticks(
        np.cumsum(data[:, 5]),
        np.cumsum(data[:, 4]),
        per_count,
        per_count,
        geometry.wheel_base_m,
    )
    label = _RUN_NAME.match(path.name)
    run = f"run-{label['run']}" if label else path.stem
    return Recording(
        source=str(path),
        t_s=data[:, 0],
        odometry=odometry,
        truth=data[:, 1:4],
        where=lines,
        unit="line",
        trial=(run,) * rows,
    )


def joined_runs(paths: list[Path], gap_s: float = 0.05) -> Recording:
    """The runs the paths name (:func:`run_files`) as one recording with a
    trial label per run (``<session>_run-NN``), each run's times shifted to
    follow the previous run's after ``gap_s``, its odometry and ground truth as
    read: what :func:`odohil.session.trials.logs.csv_log.write_csv_log` writes as an
    odohil log CSV that reads back to the same trials (each run's ground truth
    stays in its own start frame; the trial column keeps them apart)."""
    runs = [read_run(path) for path in run_files(paths)]
    if not runs:
        raise RecordingError("no optiodom run file given")
    times, labels, offset = [], [], 0.0
    for path, run in zip(run_files(paths), runs, strict=True):
        times.append(run.t_s - run.t_s[0] + offset)
        offset = float(times[-1][-1]) + gap_s
        labels.extend([path.stem] * len(run.t_s))
    t = np.concatenate(times)
    return Recording(
        source=", ".join(str(path) for path in paths),
        t_s=t,
        odometry=np.concatenate([run.odometry for run in runs]),
        truth=np.concatenate([run.truth for run in runs]),
        where=np.arange(2, 2 + len(t), dtype=np.int64),
        unit="line",
        trial=tuple(labels),
    )


def read_optiodom(paths: list[Path], description: RobotDescription, options: ImportOptions) -> Cut:
    """The trials of optiodom run files and folders (module docstring), one
    per run, numbered from 1 in file order."""
    cuts: list[Cut] = []
    runs = run_files(paths)
    quiet = replace(options, progress=None)  # one stage: the runs, not each run's cut
    with stage(options.progress, READING, len(runs)) as tell:
        for done, path in enumerate(runs):
            tell(done, len(runs))
            cuts.append(cut_of(read_run(path), description, quiet, next_number(cuts)))
    return joined(cuts)


READING = "reading runs"
"""The progress stage of :func:`read_optiodom` (counts: run files)."""
