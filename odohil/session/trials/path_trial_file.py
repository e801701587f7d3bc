"""General-path trial files: JSON lines, one :class:`PathTrial` per line.

What ``odohil import`` writes and the general-path estimator reads. The first
line is a header, every other line one trial::

    {"format": "odohil-path-trials", "version": 1, "trials": 2, "robot": "create2"}
    {"trial": 1, "source": "log.csv", "span_s": [1.8, 7.2], "family": "straight",
     "direction": "forward", "steps": [{"leg_m": 0.5}, {"turn_rad": 0.01, "kind": "arc"}, ...],
     "pose_change": [1.01, 0.0001, -0.00005],
     "measurement_cov": [[...], [...], [...]], "name": "log.csv trial 1"}

(one line each; wrapped here). Units: ``leg_m`` metres (negative: driven
backwards), ``turn_rad`` radians counter-clockwise with its ``kind`` (``spin``
or ``arc``), ``pose_change`` (x m, y m, heading change rad minus the path's
winding, :class:`~odohil.science.path_trials.PathTrial`), ``measurement_cov``
its 3x3 covariance (m^2, m rad, rad^2), ``span_s`` seconds in the source or
null. Floats are written as ``repr`` does, so a file reads back to the same
numbers. A reader refuses a newer ``version`` than it knows.
"""

from __future__ import annotations

import json
import math
import os
import tempfile
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from odohil import units
from odohil.errors import OdohilError, TrialFileError
from odohil.science.path_trials import PathTrial
from odohil.science.paths import TURN_KINDS, EncoderPath, Leg, Step, Turn
from odohil.session.trials.logs.files import check_regular

FORMAT = "odohil-path-trials"
VERSION = 1
MAX_FILE_BYTES = 256 * 1024 * 1024
"""Largest trial file read, bytes."""
MAX_TRIALS = 1_000_000
"""Most trials in one file."""
MAX_STEPS = 100_000
"""Most steps of one trial's path."""
DIRECTIONS = ("forward", "backward", "cw", "ccw", "mixed")


def _step(step: Step) -> dict[str, Any]:
    if isinstance(step, Leg):
        return {"leg_m": step.length_m}
    return {"turn_rad": step.angle_rad, "kind": step.kind}


def trial_record(trial: PathTrial) -> dict[str, Any]:
    """One trial as the JSON object of its line."""
    return {
        "trial": trial.trial,
        "source": trial.source,
        "span_s": None if trial.span_s is None else list(trial.span_s),
        "family": trial.family,
        "direction": trial.direction,
        "steps": [_step(step) for step in trial.path.steps],
        "pose_change": [float(v) for v in trial.pose_change],
        "measurement_cov": [[float(v) for v in row] for row in trial.measurement_cov],
        "name": trial.path.name,
    }


def write_path_trials(path: str | Path, trials: Iterable[PathTrial], robot: str = "") -> int:
    """Write the trials to ``path`` (replaced only once fully written, so a
    reader never sees half a file); returns the number written."""
    rows = [json.dumps(trial_record(t), allow_nan=False) for t in trials]
    header = {"format": FORMAT, "version": VERSION, "trials": len(rows), "robot": robot}
    target = Path(path)
    handle, temporary = tempfile.mkstemp(dir=target.parent or ".", prefix=f".{target.name}.")
    try:
        with os.fdopen(handle, "w", encoding="utf-8") as stream:
            stream.write(json.dumps(header) + "\n")
            for row in rows:
                stream.write(row + "\n")
        os.replace(temporary, target)
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise
    return len(rows)


def _number(value: Any, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise TrialFileError(f"{where}: a finite number is expected, got {value!r}")
    return float(value)


def _steps(value: Any, where: str) -> tuple[Step, ...]:
    if not isinstance(value, list) or not value or len(value) > MAX_STEPS:
        raise TrialFileError(f"{where}: steps: a list of 1 to {MAX_STEPS} steps is expected")
    steps: list[Step] = []
    for index, item in enumerate(value):
        at = f"{where}: steps[{index}]"
        if isinstance(item, dict) and set(item) == {"leg_m"}:
            steps.append(Leg(_number(item["leg_m"], f"{at}.leg_m")))
        elif isinstance(item, dict) and set(item) == {"turn_rad", "kind"}:
            if item["kind"] not in TURN_KINDS:
                raise TrialFileError(f"{at}.kind: one of {TURN_KINDS}, got {item['kind']!r}")
            steps.append(Turn(_number(item["turn_rad"], f"{at}.turn_rad"), item["kind"]))
        else:
            raise TrialFileError(
                f'{at}: {{"leg_m": L}} or {{"turn_rad": A, "kind": "spin"|"arc"}} expected, '
                f"got {item!r}"
            )
    return tuple(steps)


def _trial(record: Any, where: str) -> PathTrial:
    if not isinstance(record, dict):
        raise TrialFileError(f"{where}: a JSON object is expected")
    known = {
        "trial",
        "source",
        "span_s",
        "family",
        "direction",
        "steps",
        "pose_change",
        "measurement_cov",
        "name",
    }
    missing = [key for key in ("steps", "pose_change", "measurement_cov") if key not in record]
    if missing:
        raise TrialFileError(f"{where}: missing {', '.join(missing)}")
    unknown = [key for key in record if key not in known]
    if unknown:
        raise TrialFileError(f"{where}: unknown key(s) {', '.join(unknown)}")
    number = record.get("trial")
    if number is not None and (isinstance(number, bool) or not isinstance(number, int)):
        raise TrialFileError(f"{where}: trial: an integer or null, got {number!r}")
    span = record.get("span_s")
    if span is not None:
        if not isinstance(span, list) or len(span) != 2:
            raise TrialFileError(f"{where}: span_s: [start, end] in seconds or null")
        span = (_number(span[0], f"{where}: span_s[0]"), _number(span[1], f"{where}: span_s[1]"))
    direction = record.get("direction", "mixed")
    if direction not in DIRECTIONS:
        raise TrialFileError(f"{where}: direction: one of {DIRECTIONS}, got {direction!r}")
    pose = record["pose_change"]
    if not isinstance(pose, list) or len(pose) != 3:
        raise TrialFileError(f"{where}: pose_change: [x_m, y_m, dtheta_rad] expected")
    cov = record["measurement_cov"]
    if (
        not isinstance(cov, list)
        or len(cov) != 3
        or any(not isinstance(row, list) or len(row) != 3 for row in cov)
    ):
        raise TrialFileError(f"{where}: measurement_cov: a 3x3 list of lists expected")
    for key in ("source", "family", "name"):
        if not isinstance(record.get(key, ""), str):
            raise TrialFileError(f"{where}: {key}: a string expected")
    try:
        path = EncoderPath(_steps(record["steps"], where), name=record.get("name", ""))
        return PathTrial(
            path=path,
            pose_change=np.array([_number(v, f"{where}: pose_change") for v in pose]),
            measurement_cov=np.array(
                [[_number(v, f"{where}: measurement_cov") for v in row] for row in cov]
            ),
            source=record.get("source", ""),
            span_s=span,
            trial=number,
            family=record.get("family", "path"),
            direction=direction,
        )
    except TrialFileError:
        raise
    except OdohilError as exc:
        raise TrialFileError(f"{where}: {exc}") from None


def parse_path_trials(text: str, source: str = "trial file") -> list[PathTrial]:
    """Parse the text of a general-path trial file (module docstring).

    Raises:
        TrialFileError: not such a file, a newer version, a bad line (the
            message names the line and the key), or a trial count that
            disagrees with the header.
    """
    lines = text.splitlines()
    if not lines:
        raise TrialFileError(f"{source}: empty; not a general-path trial file")
    try:
        header = json.loads(lines[0])
    except json.JSONDecodeError:
        header = None
    if not isinstance(header, dict) or header.get("format") != FORMAT:
        raise TrialFileError(f"{source} line 1: not a general-path trial file (format {FORMAT})")
    version = header.get("version")
    if not isinstance(version, int) or isinstance(version, bool) or not 1 <= version <= VERSION:
        raise TrialFileError(
            f"{source} line 1: version: {version!r}; this odohil reads versions 1-{VERSION}"
        )
    trials: list[PathTrial] = []
    for number, line in enumerate(lines[1:], start=2):
        if not line.strip():
            continue
        where = f"{source} line {number}"
        try:
            record = json.loads(line)
        except json.JSONDecodeError as exc:
            raise TrialFileError(f"{where}: not JSON: {exc.msg}") from None
        trials.append(_trial(record, where))
        if len(trials) > MAX_TRIALS:
            raise TrialFileError(f"{source}: more than {units.plural(MAX_TRIALS, 'trial')}")
    expected = header.get("trials")
    if expected is not None and expected != len(trials):
        raise TrialFileError(
            f"{source} line 1: trials: the header says {expected!r}, the file holds {len(trials)} "
            "(a file cut short?)"
        )
    return trials


def read_path_trials(path: str | Path) -> list[PathTrial]:
    """Read a general-path trial file (module docstring).

    Raises:
        TrialFileError: see :func:`parse_path_trials`; also a file that cannot
            be read or is larger than :data:`MAX_FILE_BYTES`.
    """
    file = Path(path)
    try:
        check_regular(file, MAX_FILE_BYTES)
        text = file.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError, OdohilError) as exc:
        raise TrialFileError(f"cannot read trial file {file}: {exc}") from None
    return parse_path_trials(text, source=str(file))


def is_path_trial_file(path: str | Path) -> bool:
    """Whether ``path`` is a regular file whose first line is this format's
    header (to tell it from a recording or a pose-trial CSV)."""
    file = Path(path)
    if not file.is_file():
        return False
    try:
        with open(file, "rb") as stream:
            first = stream.readline(4096)
        header = json.loads(first)
    except (OSError, ValueError):
        return False
    return isinstance(header, dict) and header.get("format") == FORMAT


def summary_rows(trials: Sequence[PathTrial]) -> list[tuple[str, str, int, float]]:
    """(family, direction, trials, distance m) per group, in first-seen order."""
    groups: dict[tuple[str, str], list[float]] = {}
    for trial in trials:
        groups.setdefault((trial.family, trial.direction), []).append(trial.path.distance_m)
    return [(f, d, len(v), float(sum(v))) for (f, d), v in groups.items()]
