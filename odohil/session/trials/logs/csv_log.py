"""odohil's own log format: one CSV file of odometry and ground truth.

A header line names the columns (any order; blank lines and lines starting
with ``#`` are skipped)::

    t_s,odo_x_m,odo_y_m,odo_theta_rad,true_x_m,true_y_m,true_theta_rad[,trial]
    t_s,ticks_left,ticks_right,true_x_m,true_y_m,true_theta_rad[,trial]

- ``t_s``: time, s, strictly increasing;
- the odometry, either as poses ``odo_x_m,odo_y_m,odo_theta_rad`` (m, m,
  rad, the robot's own odometry frame) or as cumulative wheel encoder counts
  ``ticks_left,ticks_right`` (turned into poses with the robot description's
  ``[robot]`` ``counts_per_rev``, ``wheel_diameter_m`` (one number or
  ``[left, right]``) and ``wheel_base_m``);
- the ground truth ``true_x_m,true_y_m,true_theta_rad`` in any world frame
  (a row may leave all three empty where the capture lost the robot; a gap
  longer than ``--max-truth-gap`` inside a trial is an error);
- ``trial`` (optional): a label per row; the rows of one label form one
  trial, rows with an empty label lie between trials. Without it the log is
  cut at rest (odohil/science/rest_cutting.py).

Several files are read one after the other; their trials are numbered on.
"""

from __future__ import annotations

import csv
import math
import operator
import warnings
from contextlib import closing
from dataclasses import dataclass
from itertools import chain
from pathlib import Path

import numpy as np
import numpy.typing as npt

from odohil.errors import RecordingError
from odohil.science.odometry_paths import integrate_ticks
from odohil.science.paths import FloatArray
from odohil.science.robot_description import RobotDescription
from odohil.session.progress import Progress, Tell, stage
from odohil.session.trials.logs.files import finite_number, read_pieces, read_text
from odohil.session.trials.logs.recording import (
    ImportOptions,
    IntArray,
    Recording,
    check_increasing,
)
from odohil.session.trials.logs.windows import Cut, cut_of, joined, next_number

__all__ = [
    "TIME_COLUMN",
]

TIME_COLUMN = "t_s"
POSE_COLUMNS = ("odo_x_m", "odo_y_m", "odo_theta_rad")
TICK_COLUMNS = ("ticks_left", "ticks_right")
TRUTH_COLUMNS = ("true_x_m", "true_y_m", "true_theta_rad")
TRIAL_COLUMN = "trial"
KNOWN_COLUMNS = (TIME_COLUMN, *POSE_COLUMNS, *TICK_COLUMNS, *TRUTH_COLUMNS, TRIAL_COLUMN)
MAX_ROWS = 5_000_000
"""Most rows of one log file."""
MAX_TRIAL_LABEL = 200
"""Longest ``trial`` label, characters."""


def _header(path: Path, fields: list[str], line: int) -> tuple[str, ...]:
    names = tuple(name.strip() for name in fields)
    unknown = [name for name in names if name not in KNOWN_COLUMNS]
    if unknown:
        raise RecordingError(
            f"{path} line {line}: unknown column(s) {', '.join(map(repr, unknown))}; "
            f"known: {', '.join(KNOWN_COLUMNS)}"
        )
    if len(set(names)) != len(names):
        raise RecordingError(f"{path} line {line}: a column is named twice: {list(names)}")
    has_pose = [name in names for name in POSE_COLUMNS]
    has_ticks = [name in names for name in TICK_COLUMNS]
    if TIME_COLUMN not in names:
        raise RecordingError(f"{path} line {line}: the column t_s is missing")
    if all(has_pose) == all(has_ticks) or (any(has_pose) and any(has_ticks)):
        raise RecordingError(
            f"{path} line {line}: the odometry must be given either as "
            f"{','.join(POSE_COLUMNS)} or as {','.join(TICK_COLUMNS)}, got {list(names)}"
        )
    missing = [name for name in TRUTH_COLUMNS if name not in names]
    if missing:
        raise RecordingError(
            f"{path} line {line}: the ground-truth column(s) {', '.join(missing)} are missing"
        )
    return names


_COMMAS = operator.methodcaller("count", ",")
_NEWLINE, _COMMA, _SPACE = 10, 44, 32
_NOT_IN_NUMBERS = np.zeros(256, dtype=np.bool_)
_NOT_IN_NUMBERS[np.frombuffer(b' \t\r"#', dtype=np.uint8)] = True
"""Bytes that send a piece to the other readers when among the numbers
(``fromstring`` skips white space where ``float`` would refuse a blank field)."""
_PIECE_BYTES = 4 * 1024 * 1024
"""Bytes of the file parsed at once by the piecewise reader."""
_CHUNK_CHARS = 4 * 1024 * 1024
"""Characters of text split into rows at once by the fast reader (bounds its
lists of fields to a few tens of MB whatever the log's size)."""


@dataclass(frozen=True)
class _Rows:
    """A log's rows as arrays (what :class:`Recording` is made of)."""

    names: tuple[str, ...]
    t_s: FloatArray
    odometry: FloatArray
    truth: FloatArray
    where: IntArray
    labels: list[str]


class _SlowPath(Exception):
    """The fast reader met something it does not check itself."""


def _first_line(text: str) -> tuple[int, int, str] | None:
    """(line number, offset after it, the line) of the first line that is
    neither blank nor a comment, or None (also when a line before it ends
    otherwise than with a newline: the slow reader counts such lines)."""
    offset = 0
    number = 0
    while offset < len(text):
        end = text.find("\n", offset)
        end = len(text) if end < 0 else end + 1
        line = text[offset:end]
        offset = end
        number += 1
        if len(line.splitlines()) > 1:
            return None
        if line.strip() and not line.lstrip().startswith("#"):
            return number, offset, line.rstrip("\r\n")
    return None


def _fast_rows(path: Path, text: str, chunk_chars: int = _CHUNK_CHARS) -> _Rows | None:
    """The rows of ``text`` parsed column by column, a few MB at a time
    (``float`` over each column: the numbers ``finite_number`` gives), or
    None when anything needs a check the slow reader makes (quotes, a line
    that is blank, a comment or has the wrong number of fields, a field that
    is not a finite number, a truth pose partly empty, a long label): the
    slow reader then names the line and the field."""
    if '"' in text:
        return None
    found = _first_line(text)
    if found is None:
        return None
    header_line, offset, header = found
    names = _header(path, next(csv.reader([header])), header_line)
    columns = len(names)
    odo_names = POSE_COLUMNS if POSE_COLUMNS[0] in names else TICK_COLUMNS
    numeric = [TIME_COLUMN, *odo_names, *TRUTH_COLUMNS]
    index = {name: names.index(name) for name in names}
    parts: dict[str, list[FloatArray]] = {name: [] for name in numeric}
    labels: list[str] = []
    rows = 0
    while offset < len(text):
        end = text.find("\n", offset + chunk_chars)
        end = len(text) if end < 0 else end + 1
        chunk = text[offset:end]
        lines = chunk.splitlines()
        offset = end
        if not all(map(str.strip, lines)):
            return None
        if "#" in chunk and any(line.lstrip().startswith("#") for line in lines):
            return None
        if set(map(_COMMAS, lines)) != {columns - 1}:
            return None
        fields = ",".join(lines).split(",")
        rows += len(lines)
        if rows > MAX_ROWS:
            return None
        try:
            for name in numeric:
                parts[name].append(_floats(fields[index[name] :: columns], name in TRUTH_COLUMNS))
        except ValueError:
            return None
        if TRIAL_COLUMN in index:
            given = list(map(str.strip, fields[index[TRIAL_COLUMN] :: columns]))
            if given and max(map(len, given)) > MAX_TRIAL_LABEL:
                return None
            labels.extend(given)
        del fields, lines, chunk
    if rows == 0:
        return None
    values = {name: np.concatenate(parts.pop(name)) for name in numeric}
    truth = np.stack([values.pop(name) for name in TRUTH_COLUMNS], axis=1)
    missing = ~np.isfinite(truth)
    # a truth pose is all numbers or all empty (NaN only where the text was empty)
    if not (np.all(missing.all(axis=1) | ~missing.any(axis=1))):
        return None
    odometry = np.stack([values.pop(name) for name in odo_names], axis=1)
    t = values.pop(TIME_COLUMN)
    if not (np.isfinite(t).all() and np.isfinite(odometry).all()):
        return None
    if missing.any() and _nan_written(text):
        return None
    where = np.arange(header_line + 1, header_line + 1 + rows, dtype=np.int64)
    return _Rows(names, t, odometry, truth, where, labels)


def _piece_rows(
    path: Path, piece_bytes: int = _PIECE_BYTES, tell: Tell | None = None
) -> _Rows | None:
    """The rows of the log at ``path``, read a piece of a few MB at a time
    and parsed without a Python object per number (:func:`_piece_values`),
    or None for anything :func:`_fast_rows` or the slow reader must see (the
    file is then read whole; errors of reading raise here already)."""
    pieces = read_pieces(path, piece_bytes=piece_bytes)
    with closing(pieces):
        first, found = b"", None
        while found is None:
            piece = next(pieces, None)
            if piece is None:
                return None
            first += piece
            try:
                text = first.decode("utf-8")
            except UnicodeDecodeError:
                return None
            found = _first_line(text)
        if '"' in text[: found[1]]:
            return None
        header_line, offset, header = found
        names = _header(path, next(csv.reader([header])), header_line)
        odo_names = POSE_COLUMNS if POSE_COLUMNS[0] in names else TICK_COLUMNS
        numeric = [TIME_COLUMN, *odo_names, *TRUTH_COLUMNS]
        label = names.index(TRIAL_COLUMN) if TRIAL_COLUMN in names else None
        parts: list[FloatArray] = []
        labels: list[str] = []
        rows = 0
        size, done = _size(path), 0
        for piece in chain([first[len(text[:offset].encode("utf-8")) :]], pieces):
            if tell is not None:  # bytes parsed before this piece
                tell(done, size)
                done += len(piece)
            parsed = _piece_values(piece, len(names), label)
            if parsed is None:
                return None
            values, given = parsed
            rows += values.shape[0]
            if rows > MAX_ROWS:
                return None
            parts.append(values)
            labels.extend(given)
    if rows == 0:
        return None
    table = np.concatenate(parts)
    del parts
    kept = [name for name in names if name != TRIAL_COLUMN]
    columns = [kept.index(name) for name in numeric]
    if not np.isfinite(table).all():
        return None
    t = np.ascontiguousarray(table[:, columns[0]])
    odometry = np.ascontiguousarray(table[:, columns[1 : 1 + len(odo_names)]])
    truth = np.ascontiguousarray(table[:, columns[1 + len(odo_names) :]])
    where = np.arange(header_line + 1, header_line + 1 + rows, dtype=np.int64)
    return _Rows(names, t, odometry, truth, where, labels)


def _piece_values(
    piece: bytes, columns: int, label: int | None
) -> tuple[FloatArray, list[str]] | None:
    """The numbers of a piece of whole lines, (rows, numeric columns), by one
    ``np.fromstring`` over its bytes with the trial labels blanked out and
    the newlines made commas, and the labels; None unless every line has
    ``columns`` fields, no space, tab, CR, quote or comment among the numbers
    and every number field is one number (the other readers then look)."""
    if not piece:
        return np.empty((0, columns - (label is not None))), []
    if not piece.endswith(b"\n"):
        piece += b"\n"
    data = np.frombuffer(piece, dtype=np.uint8).copy()
    ends = np.flatnonzero(data == _NEWLINE)
    commas = np.flatnonzero(data == _COMMA)
    lines = ends.size
    if commas.size != lines * (columns - 1):
        return None
    per_line = commas.reshape(lines, columns - 1)
    starts = np.concatenate(([0], ends[:-1] + 1))
    if not (np.all(per_line[:, 0] >= starts) and np.all(per_line[:, -1] < ends)):
        return None  # a newline inside a line's commas: a short or long line
    given: list[str] = []
    if label is not None:
        first = starts if label == 0 else per_line[:, label - 1] + 1
        stop = ends if label == columns - 1 else per_line[:, label]
        inside = np.zeros(data.size + 1, dtype=np.int8)
        inside[first] += 1
        inside[stop] -= 1
        in_label = np.cumsum(inside[:-1], dtype=np.int64) > 0
        if _NOT_IN_NUMBERS[data[~in_label]].any():
            return None
        kept = data[in_label | _at(data.size, stop)]
        kept[kept == _COMMA] = _NEWLINE
        try:
            raw = kept.tobytes().decode("utf-8").splitlines()
        except UnicodeDecodeError:
            return None
        if len(raw) != lines or any('"' in value for value in raw):
            return None  # a line break splitlines sees inside a label, a quote
        stripped = {value: value.strip() for value in set(raw)}
        if max(map(len, stripped.values())) > MAX_TRIAL_LABEL:
            return None
        if label == 0 and any(value.startswith("#") for value in stripped.values()):
            return None  # a comment line
        given = list(map(stripped.__getitem__, raw))
        data[in_label] = _SPACE
        data[stop if label < columns - 1 else first - 1] = _SPACE
    elif _NOT_IN_NUMBERS[data].any():
        return None
    data[ends] = _COMMA
    with warnings.catch_warnings():
        warnings.simplefilter("error", DeprecationWarning)
        try:
            values = np.fromstring(data.tobytes(), dtype=np.float64, sep=",")
        except (ValueError, DeprecationWarning):
            return None
    numbers = columns - (label is not None)
    if values.size != lines * numbers:
        return None
    return values.reshape(lines, numbers), given


def _at(size: int, positions: IntArray) -> npt.NDArray[np.bool_]:
    mask = np.zeros(size, dtype=np.bool_)
    mask[positions] = True
    return mask


def _floats(column: list[str], may_be_empty: bool) -> FloatArray:
    """``float`` of every field (NaN for an empty one where ``may_be_empty``).

    Raises:
        ValueError: a field that is not a number.
    """
    try:
        return np.fromiter(map(float, column), np.float64, len(column))
    except ValueError:
        if not may_be_empty:
            raise
    filled = [value if value.strip() else "nan" for value in column]
    return np.fromiter(map(float, filled), np.float64, len(filled))


def _nan_written(text: str) -> bool:
    """Whether the text spells a non-finite number (``nan``, ``inf``), which
    the fast reader cannot tell from an empty field after parsing."""
    lowered = text.lower()
    return "nan" in lowered or "inf" in lowered


def _checked_rows(path: Path, text: str) -> _Rows:
    """The rows of ``text`` line by line, each field checked (the first bad one raises)."""
    names: tuple[str, ...] | None = None
    times: list[float] = []
    odometry: list[list[float]] = []
    truth: list[list[float]] = []
    labels: list[str] = []
    where: list[int] = []
    for number, line in enumerate(text.splitlines(), start=1):
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        fields = next(csv.reader([line]))
        if names is None:
            names = _header(path, fields, number)
            continue
        if len(fields) != len(names):
            raise RecordingError(
                f"{path} line {number}: {len(fields)} fields; the header names {len(names)}"
            )
        row = dict(zip(names, (field.strip() for field in fields), strict=True))
        times.append(finite_number(path, number, TIME_COLUMN, row[TIME_COLUMN]))
        odo_names = POSE_COLUMNS if POSE_COLUMNS[0] in row else TICK_COLUMNS
        odometry.append([finite_number(path, number, name, row[name]) for name in odo_names])
        given = [row[name] for name in TRUTH_COLUMNS]
        if all(value == "" for value in given):
            truth.append([math.nan] * 3)
        else:
            truth.append(
                [
                    finite_number(path, number, name, value)
                    for name, value in zip(TRUTH_COLUMNS, given, strict=True)
                ]
            )
        label = row.get(TRIAL_COLUMN, "")
        if len(label) > MAX_TRIAL_LABEL:
            raise RecordingError(
                f"{path} line {number}: trial: a label of at most {MAX_TRIAL_LABEL} characters"
            )
        labels.append(label)
        where.append(number)
        if len(times) > MAX_ROWS:
            raise RecordingError(f"{path}: more than {MAX_ROWS} rows")
    if names is None:
        raise RecordingError(f"{path}: no header line; no trial in the log")
    if not times:
        raise RecordingError(f"{path}: a header but no rows; no trial in the log")
    return _Rows(
        names,
        np.array(times, dtype=np.float64),
        np.array(odometry, dtype=np.float64),
        np.array(truth, dtype=np.float64),
        np.array(where, dtype=np.int64),
        labels,
    )


def _size(path: Path) -> int:
    """The file's size in bytes, at least 1 (a progress total; 1 for what is no file)."""
    return max(path.stat().st_size, 1) if path.is_file() else 1


def read_csv_log(
    path: Path, description: RobotDescription, progress: Progress | None = None
) -> Recording:
    """One odohil log CSV as a recording (module docstring).

    The usual log (no quotes, comments or blank lines among the rows, every
    field a finite number or an empty truth pose) is parsed column by column
    with numpy; anything else, line by line, so that the first bad line and
    field are named.

    Raises:
        RecordingError: unreadable file, bad header, a bad value (the message
            names the line and the column), time not increasing.
    """
    with stage(progress, f"reading {path.name}", _size(path)) as tell:
        parsed = _piece_rows(path, tell=tell)
    if parsed is None:
        text = read_text(path)
        parsed = _fast_rows(path, text) or _checked_rows(path, text)
        del text
    names, t, lines, odo = parsed.names, parsed.t_s, parsed.where, parsed.odometry
    check_increasing(t, lines, str(path), TIME_COLUMN, "line")
    if odo.shape[1] == 2:
        drive = description.robot.drive
        if drive is None:
            raise RecordingError(
                f"{path}: wheel counts need the robot's counts_per_rev, wheel_diameter_m and "
                "wheel_base_m in the robot description's [robot] table"
            )
        left, right = drive.wheel_metres_per_count
        odo = integrate_ticks(odo[:, 0], odo[:, 1], left, right, drive.wheel_base_m)
    return Recording(
        source=str(path),
        t_s=t,
        odometry=odo,
        truth=parsed.truth,
        where=lines,
        unit="line",
        trial=tuple(parsed.labels) if TRIAL_COLUMN in names else None,
    )


def read_csv_logs(paths: list[Path], description: RobotDescription, options: ImportOptions) -> Cut:
    """The trials of odohil log CSV files, numbered from 1 in file order."""
    cuts: list[Cut] = []
    for path in paths:
        recording = read_csv_log(path, description, options.progress)
        cuts.append(cut_of(recording, description, options, next_number(cuts)))
    return joined(cuts)


def write_csv_log(path: Path, recording: Recording) -> None:
    """Write a recording as an odohil log CSV (odometry as poses; floats as
    ``repr`` so that reading gives back the same numbers): a converter's and
    the tests' writer."""
    columns = [TIME_COLUMN, *POSE_COLUMNS, *TRUTH_COLUMNS]
    if recording.trial is not None:
        columns.append(TRIAL_COLUMN)
    with open(path, "w", encoding="utf-8", newline="") as stream:
        writer = csv.writer(stream, lineterminator="\n")
        writer.writerow(columns)
        for index in range(len(recording.t_s)):
            truth = recording.truth[index]
            row = [repr(float(recording.t_s[index]))]
            row += [repr(float(v)) for v in recording.odometry[index]]
            row += (
                ["", "", ""] if not np.all(np.isfinite(truth)) else [repr(float(v)) for v in truth]
            )
            if recording.trial is not None:
                row.append(recording.trial[index])
            writer.writerow(row)
