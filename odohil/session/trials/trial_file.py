"""Trial files: CSV rows of measured pose changes or raw floor-mark distances.

Formats (see docs/measurements.md), one row per line, with a header:

- pose changes: ``k,l_m,variant,dx_m,dy_m,dtheta_rad``;
- raw marks: ``k,l_m,variant,d1_m,d2_m,d3_m,cross1_m[,cross2_m]`` (one ``d`` per
  screw and one ``cross`` per cross pair of the robot description, in its order);

either with the optional odometry end pose ``odo_x_m,odo_y_m,odo_theta_rad``
(default: the design's ideal encoder end pose). Blank lines and lines starting
with ``#`` are ignored.
"""

from __future__ import annotations

import csv
import math
import os
import tempfile
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np
import numpy.typing as npt

from odohil.errors import MeasurementError, ParameterError, TrialFileError
from odohil.science.floor_marks import MarkDistances, PoseDistribution
from odohil.science.grouping import by_design
from odohil.science.paths import VARIANTS, Design, Variant
from odohil.science.pose_selection import ParameterBelief, predictive_pose, select_pose
from odohil.science.robot_description import RobotDescription
from odohil.session.bounded_io import MIB, read_file_text

FloatArray = npt.NDArray[np.float64]
TrialKind = Literal["pose", "marks"]
PriorForDesign = Callable[[Design], PoseDistribution]
"""The model's predicted pose-change distribution of one trial of a design."""

DESIGN_COLUMNS = ("k", "l_m", "variant")
BACKWARD_SUFFIX = "-backward"
"""Appended to the variant of a trial driven backwards (e.g. ``turn-backward``)."""
POSE_COLUMNS = ("dx_m", "dy_m", "dtheta_rad")
ODOMETRY_COLUMNS = ("odo_x_m", "odo_y_m", "odo_theta_rad")
MAX_LINE_CHARS = 4096
"""Longest line of a trial file (csv's own field limit is 128 KiB)."""
MAX_ROWS = 100_000
"""Most trial rows in one file."""
MAX_FILE_BYTES = 32 * MIB
"""Largest trial file (or pose file), bytes: 100,000 rows of over 300 bytes each."""
MAX_LINE_BYTES = 4 * MAX_LINE_CHARS
"""Longest line read, bytes (4 per UTF-8 character); :data:`MAX_LINE_CHARS` is then checked."""
MAX_POSE_M = 10_000.0
"""Largest |dx|, |dy|, |odo_x|, |odo_y| and mark distance, metres."""
MAX_ANGLE_RAD = 1_000.0
"""Largest |dtheta| and |odo_theta|, radians."""


@dataclass(frozen=True, eq=False)
class Trial:
    """One trial: its design and its measured pose change.

    Attributes:
        design: the forth-and-back design driven.
        pose_change: (dx m, dy m, dtheta rad) in the start frame.
        pose_cov: 3x3 covariance of ``pose_change`` from the tape errors (raw
            marks), or None when the file gave the pose change itself.
        marks: the raw distances (metres), or None for pose rows.
        odometry_end_pose: (x m, y m, theta rad) the odometry reported.
        flagged: True when the pose from the marks is in doubt.
        note: why the trial is flagged (empty otherwise).
        line: line number in the file (1-based).
        number: the trial's number (a session's plan trial number), or None
            (a trial file's rows are numbered by position, from 1).
    """

    design: Design
    pose_change: FloatArray
    pose_cov: FloatArray | None
    marks: MarkDistances | None
    odometry_end_pose: FloatArray
    flagged: bool = False
    note: str = ""
    line: int = 0
    number: int | None = None


@dataclass(frozen=True)
class TrialSet:
    """The trials of one file, in file order.

    Attributes:
        trials: the trials.
        kind: ``pose`` or ``marks``, the file's format.
        source: where the trials came from (a path).
        ambiguous: trials left out because two candidate poses stayed
            plausible (odohil/science/pose_selection.py); not in ``trials``.
    """

    trials: tuple[Trial, ...]
    kind: TrialKind
    source: str = ""
    ambiguous: tuple[Trial, ...] = ()

    def __len__(self) -> int:
        return len(self.trials)

    def designs(self) -> tuple[Design, ...]:
        """The distinct designs, in order of first appearance."""
        return tuple(by_design(self.trials))

    def for_design(self, design: Design) -> tuple[Trial, ...]:
        """The trials of one design, in file order."""
        return tuple(by_design(self.trials).get(design, ()))

    def flagged(self) -> tuple[Trial, ...]:
        """The trials whose pose from the marks is in doubt."""
        return tuple(trial for trial in self.trials if trial.flagged)


def read_trials(
    path: str | Path,
    description: RobotDescription | None = None,
    prior: PriorForDesign | None = None,
) -> TrialSet:
    """Read a trial file (UTF-8 CSV).

    Args:
        path: the file.
        description: the robot description; required for raw-mark files.
        prior: optional model prediction per design, used to choose among
            candidate poses of raw-mark rows; by default the predictive
            distribution from the description's ``[priors]`` and the row's
            odometry (odohil/science/pose_selection.py, as in a live session).
            Rows whose candidates stay ambiguous are left out and listed in
            :attr:`TrialSet.ambiguous`; rows the slip check doubts are flagged.

    Raises:
        TrialFileError: the file cannot be read, its header is wrong, or any
            row is bad; the message lists every bad row by line number.
    """
    file = Path(path)
    text = read_trial_text(file, "trial file")
    return parse_trials(text, description, prior, source=str(file))


def read_trial_text(file: Path, what: str) -> str:
    """The text of a trial or pose file, read within :data:`MAX_FILE_BYTES` and
    :data:`MAX_LINE_BYTES` (odohil/session/bounded_io.py).

    Raises:
        TrialFileError: not a regular file, too large, a line too long, not UTF-8.
    """
    return read_file_text(
        file,
        what=what,
        max_bytes=MAX_FILE_BYTES,
        max_line_bytes=MAX_LINE_BYTES,
        error=TrialFileError,
    )


def parse_trials(
    text: str,
    description: RobotDescription | None = None,
    prior: PriorForDesign | None = None,
    source: str = "trial file",
) -> TrialSet:
    """Parse trial-file text; see :func:`read_trials`.

    A leading byte-order mark (Excel's "CSV UTF-8") is ignored; a line longer
    than :data:`MAX_LINE_CHARS` or more than :data:`MAX_ROWS` rows is refused."""
    text = text.removeprefix("\ufeff")
    lines = [
        (number, line)
        for number, line in enumerate(text.splitlines(), start=1)
        if line.strip() and not line.lstrip().startswith("#")
    ]
    if not lines:
        raise TrialFileError(f"{source}: no header line")
    long_lines = [number for number, line in lines if len(line) > MAX_LINE_CHARS]
    if long_lines:
        raise TrialFileError(
            f"{source}: line(s) {', '.join(map(str, long_lines[:5]))} longer than "
            f"{MAX_LINE_CHARS} characters"
        )
    if len(lines) - 1 > MAX_ROWS:
        raise TrialFileError(f"{source}: {len(lines) - 1} rows; at most {MAX_ROWS} are accepted")
    header_line, header_text = lines[0]
    header = [name.strip() for name in next(csv.reader([header_text]))]
    kind, columns = _layout(header, description, f"{source}, line {header_line}")
    parser = _RowParser(kind, header, columns, description, prior)
    trials: list[Trial] = []
    ambiguous: list[Trial] = []
    problems: list[str] = []
    for number, line in lines[1:]:
        fields = [field.strip() for field in next(csv.reader([line]))]
        try:
            trial = parser.parse(fields, number)
        except MeasurementError as exc:
            problems.append(f"line {number}: {exc}")
            continue
        (ambiguous if number in parser.ambiguous_lines else trials).append(trial)
    if problems:
        raise TrialFileError(
            f"{source}: {len(problems)} bad row(s), none used:\n  " + "\n  ".join(problems)
        )
    return TrialSet(trials=tuple(trials), kind=kind, source=source, ambiguous=tuple(ambiguous))


def write_pose_trials(path: str | Path, rows: Iterable[Trial]) -> None:
    """Write trials in the pose-change format, with the odometry columns.

    Atomic: a temporary file in the same directory is renamed over ``path``
    only once fully written, so readers never see half a file. Floats are
    written with ``repr`` so that reading gives back the same numbers.

    Raises:
        MeasurementError: a trial has a non-finite pose or odometry pose.
    """
    header = DESIGN_COLUMNS + POSE_COLUMNS + ODOMETRY_COLUMNS
    body = [",".join(header)]
    for trial in rows:
        values = [*trial.pose_change.tolist(), *trial.odometry_end_pose.tolist()]
        if len(values) != 6 or not all(math.isfinite(v) for v in values):
            raise MeasurementError(
                f"trial of line {trial.line}: pose change and odometry end pose must be "
                f"three finite numbers each, got {values}"
            )
        design = trial.design
        body.append(
            ",".join([f"{design.k:g}", repr(design.l_m), design.variant_text, *map(repr, values)])
        )
    target = Path(path)
    handle, temporary = tempfile.mkstemp(
        dir=target.parent, prefix=f".{target.name}.", suffix=".tmp"
    )
    try:
        with os.fdopen(handle, "w", encoding="utf-8", newline="") as stream:
            stream.write("\n".join(body) + "\n")
            stream.flush()
            os.fsync(stream.fileno())
        os.replace(temporary, target)
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise


def _layout(
    header: list[str], description: RobotDescription | None, where: str
) -> tuple[TrialKind, tuple[str, ...]]:
    """The file kind and its required columns, from the header."""
    duplicated = sorted({name for name in header if header.count(name) > 1})
    if duplicated:
        raise TrialFileError(f"{where}: column(s) named twice: {', '.join(duplicated)}")
    is_pose = any(name in header for name in POSE_COLUMNS)
    is_marks = any(name.startswith(("d1", "cross")) for name in header)
    if is_pose == is_marks:
        raise TrialFileError(
            f"{where}: the header must name either the pose columns "
            f"{','.join(POSE_COLUMNS)} or the raw-mark columns d1_m,...,cross1_m; "
            f"got {','.join(header)}"
        )
    kind: TrialKind = "pose" if is_pose else "marks"
    if kind == "pose":
        columns: tuple[str, ...] = DESIGN_COLUMNS + POSE_COLUMNS
    else:
        if description is None:
            raise TrialFileError(f"{where}: a raw-mark file needs the robot description")
        columns = DESIGN_COLUMNS + _mark_columns(description)
    has_odometry = [name in header for name in ODOMETRY_COLUMNS]
    if any(has_odometry) and not all(has_odometry):
        raise TrialFileError(f"{where}: give all of {','.join(ODOMETRY_COLUMNS)} or none of them")
    allowed = columns + ODOMETRY_COLUMNS
    missing = [name for name in columns if name not in header]
    unknown = [name for name in header if name not in allowed]
    if missing or unknown:
        parts = []
        if missing:
            parts.append(f"missing column(s) {','.join(missing)}")
        if unknown:
            parts.append(f"unknown column(s) {','.join(unknown)}")
        raise TrialFileError(
            f"{where}: {'; '.join(parts)} (a {kind} file has {','.join(columns)}"
            f"[,{','.join(ODOMETRY_COLUMNS)}])"
        )
    return kind, columns


def _mark_columns(description: RobotDescription) -> tuple[str, ...]:
    same = tuple(f"d{n}_m" for n in range(1, len(description.screws) + 1))
    cross = tuple(f"cross{n}_m" for n in range(1, len(description.cross_pairs) + 1))
    return same + cross


class _RowParser:
    """Turns the fields of one row into a :class:`Trial`, or raises
    :class:`MeasurementError` listing everything wrong with the row."""

    def __init__(
        self,
        kind: TrialKind,
        header: list[str],
        columns: tuple[str, ...],
        description: RobotDescription | None,
        prior: PriorForDesign | None,
    ) -> None:
        self._kind = kind
        self._header = header
        self._value_columns = columns[len(DESIGN_COLUMNS) :]
        self._description = description
        self._prior = prior
        self._priors: dict[Design, PoseDistribution] = {}
        self.ambiguous_lines: set[int] = set()

    def parse(self, fields: list[str], line: int) -> Trial:
        if len(fields) != len(self._header):
            raise MeasurementError(
                f"expected {len(self._header)} fields ({','.join(self._header)}), got {len(fields)}"
            )
        row = dict(zip(self._header, fields, strict=True))
        problems: list[str] = []
        design = self._design(row, problems)
        values = [self._number(row, name, problems) for name in self._value_columns]
        odometry: list[float | None] = [
            self._number(row, name, problems) for name in ODOMETRY_COLUMNS if name in row
        ]
        if self._kind == "marks":
            for name, value in zip(self._value_columns, values, strict=True):
                if value is not None and value < 0:
                    problems.append(f"{name} is a distance and cannot be negative: {value!r}")
        if problems or design is None:
            raise MeasurementError("; ".join(problems))
        numbers = [float(v) for v in values if v is not None]
        if odometry:
            odometry_end = np.array(odometry, dtype=np.float64)
        else:
            odometry_end = np.array(design.path().encoder_end_pose(), dtype=np.float64)
        if self._kind == "pose":
            return Trial(
                design=design,
                pose_change=np.array(numbers, dtype=np.float64),
                pose_cov=None,
                marks=None,
                odometry_end_pose=odometry_end,
                line=line,
            )
        return self._solve(design, numbers, odometry_end, line)

    def _solve(
        self, design: Design, numbers: list[float], odometry_end: FloatArray, line: int
    ) -> Trial:
        description = self._description
        assert description is not None  # checked with the header
        marks = MarkDistances.of(description, numbers)
        if self._prior is not None:
            if design not in self._priors:
                self._priors[design] = self._prior(design)
            predicted = self._priors[design]
        else:
            belief = ParameterBelief.from_priors(
                description.priors, turns_exact=description.robot.turns_exact
            )
            predicted = predictive_pose(design, belief, odometry_end)
        selection = select_pose(description, marks, odometry_end, predicted)
        solution = selection.solution
        notes = [solution.reason] if solution.reason else []
        if selection.ambiguous:
            self.ambiguous_lines.add(line)
        if selection.slip.tripped:
            notes.append(selection.slip.message())
        return Trial(
            design=design,
            pose_change=solution.pose_change,
            pose_cov=solution.cov,
            marks=marks,
            odometry_end_pose=odometry_end,
            flagged=not solution.clear_cut or selection.slip.tripped,
            note="; ".join(notes),
            line=line,
        )

    @staticmethod
    def _number(row: dict[str, str], name: str, problems: list[str]) -> float | None:
        text = row[name]
        try:
            value = float(text)
        except ValueError:
            problems.append(f"{name} is not a number: {text!r}")
            return None
        if not math.isfinite(value):
            problems.append(f"{name} is not a finite number: {text!r}")
            return None
        if name in ("k", "l_m"):
            return value  # the design checks its own range
        cap = MAX_ANGLE_RAD if name.endswith("_rad") else MAX_POSE_M
        if abs(value) > cap:
            unit = "rad" if name.endswith("_rad") else "m"
            problems.append(f"{name} must be within [-{cap:g}, {cap:g}] {unit}, got {text!r}")
            return None
        return value

    def _design(self, row: dict[str, str], problems: list[str]) -> Design | None:
        k = self._number(row, "k", problems)
        l_m = self._number(row, "l_m", problems)
        variant = row["variant"]
        backward = variant.endswith(BACKWARD_SUFFIX)
        variant = variant.removesuffix(BACKWARD_SUFFIX) if backward else variant
        if variant not in VARIANTS:
            problems.append(f"variant must be one of {', '.join(VARIANTS)}, got {variant!r}")
        if k is None or l_m is None:
            return None
        chosen: Variant = "reverse" if variant == "reverse" else "turn"
        try:
            design = Design(k, l_m, chosen, backward)
        except ParameterError as exc:
            problems.append(str(exc))
            return None
        return design if variant in VARIANTS else None
