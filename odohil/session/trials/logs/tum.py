"""TUM trajectory files, in pairs: one of odometry, one of ground truth.

Each line ``timestamp tx ty tz qx qy qz qw`` (s, m, unit quaternion x y z w;
blank lines and lines starting with ``#`` skipped), as the TUM RGB-D
benchmark defines it and the evo tool writes it. A planar robot's pose is
(tx, ty) and the heading about z, ``atan2(2 (qw qz + qx qy), 1 - 2 (qy^2 +
qz^2))``. The paths come in pairs, odometry first: ``ODOM1 TRUTH1 [ODOM2
TRUTH2 ...]``. The two are associated by time as evo does
(:func:`odohil.session.trials.logs.recording.associate`: nearest stamps within
``--max-time-diff``, ``--time-offset`` added to the ground truth's) and cut
at rest.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from odohil.errors import RecordingError
from odohil.science.paths import FloatArray
from odohil.science.robot_description import RobotDescription
from odohil.session.trials.logs.files import finite_number, read_text
from odohil.session.trials.logs.recording import (
    ImportOptions,
    IntArray,
    associate,
    check_increasing,
)
from odohil.session.trials.logs.windows import Cut, cut_of, joined, next_number

FIELDS = ("timestamp", "tx", "ty", "tz", "qx", "qy", "qz", "qw")
QUATERNION_TOLERANCE = 1e-3
"""How far from 1 a quaternion's norm may be (written with 6+ digits)."""
MAX_ROWS = 5_000_000
"""Most poses of one file."""


def heading_of(qx: float, qy: float, qz: float, qw: float) -> float:
    """The heading about z (rad) of a unit quaternion."""
    return math.atan2(2.0 * (qw * qz + qx * qy), 1.0 - 2.0 * (qy * qy + qz * qz))


def read_tum(path: Path) -> tuple[FloatArray, FloatArray, IntArray]:
    """Times (n,, s), planar poses (n, 3: x m, y m, heading rad) and line
    numbers of one TUM file.

    Raises:
        RecordingError: unreadable file; a line without eight numbers, a
            quaternion that is not of unit norm (the message names the line and
            the field); time not increasing; no pose.
    """
    times: list[float] = []
    poses: list[tuple[float, float, float]] = []
    where: list[int] = []
    for number, line in enumerate(read_text(path).splitlines(), start=1):
        text = line.strip()
        if not text or text.startswith("#"):
            continue
        fields = text.replace(",", " ").split()
        if len(fields) != len(FIELDS):
            raise RecordingError(
                f"{path} line {number}: {len(fields)} fields; a TUM line has "
                f"{len(FIELDS)}: {' '.join(FIELDS)}"
            )
        values = [
            finite_number(path, number, name, field)
            for name, field in zip(FIELDS, fields, strict=True)
        ]
        t, x, y, _, qx, qy, qz, qw = values
        norm = math.sqrt(qx * qx + qy * qy + qz * qz + qw * qw)
        if abs(norm - 1.0) > QUATERNION_TOLERANCE:
            raise RecordingError(
                f"{path} line {number}: qx qy qz qw: not a unit quaternion (norm {norm:.6g})"
            )
        times.append(t)
        poses.append((x, y, heading_of(qx, qy, qz, qw)))
        where.append(number)
        if len(times) > MAX_ROWS:
            raise RecordingError(f"{path}: more than {MAX_ROWS} poses")
    if not times:
        raise RecordingError(f"{path}: no pose; no trial in the log")
    t_s = np.array(times, dtype=np.float64)
    lines = np.array(where, dtype=np.int64)
    check_increasing(t_s, lines, str(path), "timestamp", "line")
    return t_s, np.array(poses, dtype=np.float64), lines


def read_tum_pairs(paths: list[Path], description: RobotDescription, options: ImportOptions) -> Cut:
    """The trials of TUM file pairs (odometry, ground truth), numbered from 1."""
    if len(paths) % 2:
        raise RecordingError(
            f"TUM files come in pairs (odometry, ground truth); got {len(paths)} files: "
            f"{', '.join(map(str, paths))}"
        )
    cuts: list[Cut] = []
    for odometry_path, truth_path in zip(paths[0::2], paths[1::2], strict=True):
        t_odo, odo, odo_lines = read_tum(odometry_path)
        t_truth, truth, _ = read_tum(truth_path)
        recording = associate(
            f"{odometry_path} (ground truth {truth_path.name})",
            t_odo,
            odo,
            odo_lines,
            t_truth,
            truth,
            options,
            unit="line",
            odometry_field="tx ty qz qw (odometry)",
            truth_field="tx ty qz qw (ground truth)",
        )
        cuts.append(cut_of(recording, description, options, next_number(cuts)))
    return joined(cuts)
