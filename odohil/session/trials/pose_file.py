"""Files of measured poses that serve driven general-path trials.

``--measure FILE`` with ``--port`` takes, besides the forth-and-back trial file
(odohil/session/trials/trial_file.py, rows naming ``k,l_m,variant``), two files a
user of general paths has (row k serves trial k, every attempt at it):

- a pose file: CSV with the columns ``dx_m,dy_m,dtheta_rad`` and optionally
  ``sigma_x_m,sigma_y_m,sigma_theta_rad`` (standard deviations, m and rad),
  the file ``odohil validate --path square:SIDE --measure FILE`` reads without
  ``--port``. Its rows name no path, so it serves a plan that drives one
  general path only (a validation session; ``run --plan path=...,n=N``);
- a general-path trial file (JSON lines, what ``odohil import`` writes;
  odohil/session/trials/path_trial_file.py): each row's ``steps`` must be trial k's
  path (:data:`LEG_TOLERANCE_M`, :data:`TURN_TOLERANCE_RAD`), so it serves
  any plan, forth-and-back designs included.

Poses are (x m, y m, heading change rad minus the path's winding) in the
trial's start frame. A row without a covariance is given the one the robot
description's floor marks would have at that pose
(:func:`~odohil.science.floor_marks.pose_covariance`).

:func:`check_serves` is the pre-flight check: too few rows, or a row of
another path, is refused before anything moves, naming the row and what it
should be.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np

from odohil import units
from odohil.errors import TrialFileError
from odohil.science.path_designs import PathDesign
from odohil.science.paths import Design, EncoderPath, Leg, Step, Turn
from odohil.science.robot_description import RobotDescription
from odohil.session.plans.plan import Plan
from odohil.session.trials.path_trial_file import is_path_trial_file, read_path_trials
from odohil.session.trials.trial_file import (
    DESIGN_COLUMNS,
    MAX_ANGLE_RAD,
    MAX_POSE_M,
    MAX_ROWS,
    FloatArray,
    read_trial_text,
    read_trials,
)

POSE_COLUMNS = ("dx_m", "dy_m", "dtheta_rad")
SIGMA_COLUMNS = ("sigma_x_m", "sigma_y_m", "sigma_theta_rad")
LEG_TOLERANCE_M = 0.01
"""How far a row's leg may be from the driven one's, metres, besides
:data:`LEG_TOLERANCE_REL` of its length (an imported path is measured)."""
LEG_TOLERANCE_REL = 0.02
TURN_TOLERANCE_RAD = math.radians(2.0)
"""How far a row's turn may be from the driven one's, radians."""
SHOWN = 5
"""How many mismatched rows a refusal lists."""

FileFormat = Literal["trials", "poses", "path-trials"]


@dataclass(frozen=True, eq=False)
class PoseRow:
    """One row of a pose file or a general-path trial file.

    Attributes:
        number: the row's position (1-based): it serves trial ``number``.
        line: its line in the file (1-based).
        pose: (x m, y m, heading change rad minus the path's winding).
        cov: its 3x3 covariance (m^2, m rad, rad^2), or None (the floor marks' is used).
        steps: the path the row was measured on (a general-path trial
            file), or None (a pose file: the plan's one general path).
    """

    number: int
    line: int
    pose: FloatArray
    cov: FloatArray | None
    steps: tuple[Step, ...] | None = None


def file_format(path: str | Path) -> FileFormat:
    """What ``--measure FILE`` holds: ``path-trials`` (JSON lines of ``odohil
    import``), ``poses`` (a CSV of poses without the design columns) or
    ``trials`` (a forth-and-back trial file, or anything else: its reader says
    what is wrong)."""
    if is_path_trial_file(path):
        return "path-trials"
    try:
        with open(path, encoding="utf-8-sig") as stream:
            for line in stream:
                if line.strip() and not line.lstrip().startswith("#"):
                    header = [h.strip() for h in next(csv.reader([line]))]
                    break
            else:
                return "trials"
    except (OSError, UnicodeDecodeError, csv.Error):
        return "trials"
    has_pose = any(name in header for name in POSE_COLUMNS)
    has_design = any(name in header for name in DESIGN_COLUMNS)
    return "poses" if has_pose and not has_design else "trials"


def read_pose_file(file: Path, what: str) -> list[PoseRow]:
    """The rows of a pose file (module docstring); ``what`` names its use in messages.

    Raises:
        TrialFileError: naming the file, the line and the column (every bad row).
    """
    text = read_trial_text(file, "pose file").removeprefix("\ufeff")
    lines = [
        (n, line)
        for n, line in enumerate(text.splitlines(), start=1)
        if line.strip() and not line.lstrip().startswith("#")
    ]
    if not lines:
        raise TrialFileError(f"{file}: no header line")
    header = [h.strip() for h in next(csv.reader([lines[0][1]]))]
    allowed = POSE_COLUMNS + SIGMA_COLUMNS
    missing = [c for c in POSE_COLUMNS if c not in header]
    unknown = [c for c in header if c not in allowed]
    sigmas = [c in header for c in SIGMA_COLUMNS]
    if missing or unknown or (any(sigmas) and not all(sigmas)) or len(set(header)) < len(header):
        raise TrialFileError(
            f"{file}, line {lines[0][0]}: a pose file for {what} has the columns "
            f"{','.join(POSE_COLUMNS)}[,{','.join(SIGMA_COLUMNS)}]; got {','.join(header)}"
        )
    if len(lines) - 1 > MAX_ROWS:
        raise TrialFileError(f"{file}: {len(lines) - 1} rows; at most {MAX_ROWS}")
    rows: list[PoseRow] = []
    problems: list[str] = []
    for number, line in lines[1:]:
        fields = [f.strip() for f in next(csv.reader([line]))]
        if len(fields) != len(header):
            problems.append(f"line {number}: expected {len(header)} fields, got {len(fields)}")
            continue
        values: dict[str, float] = {}
        for name, text_value in zip(header, fields, strict=True):
            try:
                value = float(text_value)
            except ValueError:
                problems.append(f"line {number}: {name} is not a number: {text_value!r}")
                continue
            cap = MAX_ANGLE_RAD if name.endswith("_rad") else MAX_POSE_M
            if (
                not math.isfinite(value)
                or abs(value) > cap
                or (name in SIGMA_COLUMNS and value < 0)
            ):
                low = 0 if name in SIGMA_COLUMNS else -cap
                problems.append(f"line {number}: {name} must be within [{low:g}, {cap:g}]")
                continue
            values[name] = value
        if len(values) != len(header):
            continue
        cov = None
        if all(sigmas):
            cov = np.diag(np.square([values[c] for c in SIGMA_COLUMNS]))
        pose = np.array([values[c] for c in POSE_COLUMNS], dtype=np.float64)
        rows.append(PoseRow(len(rows) + 1, number, pose, cov))
    if problems:
        raise TrialFileError(
            f"{file}: {len(problems)} bad row(s), none used:\n  " + "\n  ".join(problems[:20])
        )
    if not rows:
        raise TrialFileError(f"{file}: no trials")
    return rows


def read_path_rows(file: Path) -> list[PoseRow]:
    """The rows of a general-path trial file, with their paths' steps.

    Raises:
        TrialFileError: see :func:`~odohil.session.trials.path_trial_file.read_path_trials`.
    """
    trials = read_path_trials(file)
    if not trials:
        raise TrialFileError(f"{file}: no trials")
    return [
        # the header is line 1; blank lines are not expected in a written file
        PoseRow(n, n + 1, np.asarray(t.pose_change), np.asarray(t.measurement_cov), t.path.steps)
        for n, t in enumerate(trials, start=1)
    ]


def read_rows(path: str | Path) -> list[PoseRow]:
    """The rows of a pose file or a general-path trial file (:func:`file_format`).

    Raises:
        TrialFileError: the file cannot be used (a forth-and-back trial file
            is read by odohil/session/trials/trial_file.py, not here).
    """
    file = Path(path)
    kind = file_format(file)
    if kind == "path-trials":
        return read_path_rows(file)
    if kind == "poses":
        return read_pose_file(file, "driven general paths")
    raise TrialFileError(f"{file}: a forth-and-back trial file, not a file of path poses")


def _step_text(step: Step) -> str:
    if isinstance(step, Leg):
        return f"leg {step.length_m:.4g} m"
    return f"{step.kind} {step.angle_rad:.4g} rad"


def _steps_text(steps: tuple[Step, ...]) -> str:
    shown = ", ".join(_step_text(s) for s in steps[:4])
    return f"{shown}, ... ({units.plural(len(steps), 'step')})" if len(steps) > 4 else shown


def _step_problem(got: Step, want: Step) -> bool:
    if isinstance(want, Leg):
        if not isinstance(got, Leg):
            return True
        tolerance = LEG_TOLERANCE_M + LEG_TOLERANCE_REL * abs(want.length_m)
        return abs(got.length_m - want.length_m) > tolerance
    if not isinstance(got, Turn) or got.kind != want.kind:
        return True
    return abs(got.angle_rad - want.angle_rad) > TURN_TOLERANCE_RAD


def row_problem(row: PoseRow, design: Design | PathDesign) -> str:
    """Why ``row`` cannot serve a trial of ``design`` ("" when it can)."""
    if row.steps is None:
        if isinstance(design, PathDesign):
            return ""
        return (
            f"a pose file's row names no design and serves general paths only, "
            f"this trial runs {design.label()} (give a trial file with k,l_m,variant)"
        )
    return steps_problem(row, design.path(), design.label())


def steps_problem(row: PoseRow, path: EncoderPath, label: str) -> str:
    """Why the steps of ``row`` (a general-path trial file's) are not those of
    ``path`` (named ``label``), "" when they are (or the row has none)."""
    if row.steps is None:
        return ""
    want = path.steps
    if len(row.steps) != len(want):
        return (
            f"a path of {units.plural(len(row.steps), 'step')} ({_steps_text(row.steps)}), "
            f"this trial runs {label}: {_steps_text(want)}"
        )
    for index, (got, wanted) in enumerate(zip(row.steps, want, strict=True)):
        if _step_problem(got, wanted):
            return (
                f"step {index + 1} is {_step_text(got)}, this trial runs {label}, "
                f"whose step {index + 1} is {_step_text(wanted)}"
            )
    return ""


def check_serves(path: str | Path, plan: Plan, first_trial: int = 1) -> None:
    """A pose file or a general-path trial file that serves ``plan``: one row
    per trial, row k of trial k's path, for trials ``first_trial`` .. the
    plan's last (nothing has moved yet).

    Raises:
        TrialFileError: unreadable, too few rows, a pose file for a plan of
            several designs, or rows of another path (the first few listed,
            each with what it should be).
    """
    rows = read_rows(path)
    check_row_count(path, len(rows), plan)
    if rows[0].steps is None and len(plan.items) > 1:
        labels = ", ".join(item.design.label() for item in plan.items)
        raise TrialFileError(
            f"--measure {path}: a pose file's rows name no path, so it serves a plan of one "
            f"general path; this plan drives {labels}: give a general-path trial file "
            "(JSON lines, as `odohil import` writes) whose steps name each trial's path"
        )
    wrong = []
    for trial in range(first_trial, plan.n_trials + 1):
        row = rows[trial - 1]
        problem = row_problem(row, plan.design_of(trial))
        if problem:
            wrong.append(f"row {trial} (line {row.line}): {problem}")
    refuse_rows(path, wrong, "path")


def check_row_count(path: str | Path, n_rows: int, plan: Plan) -> None:
    """A file of ``n_rows`` rows for ``plan``, one per trial (``--measure``).

    Raises:
        TrialFileError: fewer rows than the plan has trials.
    """
    if n_rows < plan.n_trials:
        raise TrialFileError(
            f"--measure {path}: {units.plural(n_rows, 'row')} for a plan of "
            f"{units.plural(plan.n_trials, 'trial')}; "
            "the file needs one row per trial, in plan order"
        )


def refuse_rows(path: str | Path, wrong: list[str], what: str) -> None:
    """Refuse the rows of ``--measure`` that do not serve their trials (``wrong``:
    one line each, the first :data:`SHOWN` listed; ``what``: ``design`` or ``path``).

    Raises:
        TrialFileError: ``wrong`` is not empty.
    """
    if wrong:
        shown = "\n  ".join(wrong[:SHOWN])
        more = f"\n  ... {len(wrong) - SHOWN} more" if len(wrong) > SHOWN else ""
        raise TrialFileError(
            f"--measure {path}: {units.plural(len(wrong), 'row')} of another {what} than the "
            f"plan's:\n  {shown}{more}"
        )


def check_trial_file(
    path: str | Path, description: RobotDescription, plan: Plan, first_trial: int = 1
) -> None:
    """A trial file that serves the plan: one row per trial, row k of trial k's
    design, for trials ``first_trial`` .. the plan's last (a pose file or a
    general-path trial file).

    Raises:
        TrialFileError: the file is unreadable, has bad rows, too few rows or a
            row of another design (the first few are listed).
    """
    if file_format(path) != "trials":
        check_serves(path, plan, first_trial)
        return
    trials = read_trials(path, description)
    check_row_count(path, len(trials), plan)
    wrong = []
    for trial in range(first_trial, plan.n_trials + 1):
        row = trials.trials[trial - 1]
        wanted = plan.design_of(trial)
        if row.design != wanted:
            wrong.append(
                f"row {trial} (line {row.line}) is {row.design.label()}, "
                f"trial {trial} runs {wanted.label()}"
            )
    refuse_rows(path, wrong, "design")
