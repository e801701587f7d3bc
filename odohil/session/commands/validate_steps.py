"""What ``odohil validate`` computes besides driving (odohil/session/results/validation.py
for the parts): the robot description the held-out trials are read with, the
held-out trials of a file or a measured square, the first N of them, and the
result as its JSON document."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from odohil.errors import ParameterError
from odohil.science.robot_description import RobotDescription
from odohil.science.validation import ValidationResult
from odohil.session.journal.state import description_of_header
from odohil.session.measure.kinds import TrialFileSettings
from odohil.session.measure.registry import parse_measure
from odohil.session.results.validation import (
    Calibration,
    ValidationPath,
    ValidationTrials,
    check_not_fitted,
    default_folder,
    detectable_by_name,
    held_out_trials,
    parameter_covariance,
    predictions_of,
    read_path_poses,
)
from odohil.session.robots.description import read_robot_toml
from odohil.session.robots.registry import parse_description as parse_robot_description
from odohil.session.trials.logs import ImportOptions


def check_alpha(alpha: float) -> float:
    """``--alpha``, checked before anything moves.

    Raises:
        ParameterError: not within (0, 0.5].
    """
    if not (math.isfinite(alpha) and 0.0 < alpha <= 0.5):
        raise ParameterError(f"--alpha must be within (0, 0.5], got {alpha!r}")
    return alpha


@dataclass(frozen=True)
class CalibrationRobot:
    """The robot description of a validation: ``--robot``'s, else the session's.

    Attributes:
        description: the parsed description.
        toml: its TOML text (journaled by a driven validation session).
        path: where it was read from ("" when unknown).
    """

    description: RobotDescription
    toml: str
    path: str


def calibration_robot(calibration: Calibration, robot: Path | None) -> CalibrationRobot:
    """The robot description from ``robot`` (``--robot``), else the calibration session's.

    Raises:
        ParameterError: no ``--robot`` for a calibration that is no session,
            or a description that cannot be read.
        RobotDescriptionError: a description that cannot be used.
    """
    if robot is None:
        state = calibration.state
        if state is None:
            raise ParameterError(
                f"--robot is needed: the calibration {calibration.outcome.source} is a file or "
                "a recording, not a session (whose robot description is journaled)"
            )
        return CalibrationRobot(
            description_of_header(state),
            str(state.header["robot_toml"]),
            str(state.header.get("robot_path") or ""),
        )
    toml = read_robot_toml(robot, ParameterError, "--robot: robot description")
    return CalibrationRobot(parse_robot_description(toml, str(robot)), toml, str(robot))


def drives(vpath: ValidationPath, port: str | None, measure: str | None) -> bool:
    """Whether ``--path`` is driven and journaled as a validation session (a
    forth-and-back design; a general path unless its measured poses are
    given with ``--measure FILE`` and no ``--port``), else read from a file."""
    if vpath.kind == "file":
        return False
    if vpath.kind == "path":
        return port is not None or not _file_measure(measure)
    return True


def measured_trials(
    vpath: ValidationPath,
    calibration: Calibration,
    description: RobotDescription,
    recording: ImportOptions,
    port: str | None,
    measure: str | None,
) -> ValidationTrials:
    """The held-out trials of ``--path file:HELDOUT`` or of a general path
    whose measured poses are in ``--measure FILE`` (no ``--port``; see
    :func:`drives`); nothing is driven.

    Raises:
        ParameterError: a general path without a pose file (or with
            ``--port``: it is driven), a file design the calibration was
            fitted on.
        TrialFileError, RecordingError, MeasurementError: unusable trials.
    """
    if vpath.kind == "file":
        assert vpath.file is not None
        measured = held_out_trials(vpath.file, description, recording)
        plan = None if calibration.state is None else calibration.state.plan
        check_not_fitted(plan, [d.forward for d in measured.designs])
        return measured
    assert vpath.path is not None  # a general path
    if drives(vpath, port, measure):
        raise ParameterError(
            f"--path {vpath.text} is driven with --port and --measure fake|tcp://|FILE; "
            "its measured poses are read from --measure FILE only without --port"
        )
    return read_path_poses(Path(str(measure)), vpath.path, vpath.text)


def drive_folder(
    vpath: ValidationPath, calibration: Calibration, session: Path, out: Path | None
) -> Path:
    """The folder a driven validation (a forth-and-back design or a general
    path) is journaled in: ``out``, else SESSION/validation/<path slug>.

    Raises:
        ParameterError: the calibration is no session, or was fitted on the design.
    """
    drivable = vpath.drivable
    assert drivable is not None
    if calibration.state is None:
        raise ParameterError(
            f"--path {vpath.text} drives the robot and journals a validation session "
            f"beside the calibration's: {session} is no session; give the held-out "
            "trials with --path file:HELDOUT"
        )
    check_not_fitted(calibration.state.plan, [drivable])
    return out or default_folder(session, vpath)


def first_trials(measured: ValidationTrials, trials: int | None) -> ValidationTrials:
    """The first ``trials`` (``--trials``; None: all).

    Raises:
        ParameterError: fewer usable trials than asked for.
    """
    if trials is None:
        return measured
    if trials > len(measured):
        raise ParameterError(
            f"--trials {trials}: {measured.source} has {len(measured)} usable trials"
        )
    return measured.first(trials)


def validation_document(
    session: Path,
    vpath: ValidationPath,
    folder: Path | None,
    measured: ValidationTrials,
    calibration: Calibration,
    tested: ValidationResult,
) -> dict[str, Any]:
    """The JSON document of ``odohil validate --json`` (SI): the verdict, the
    trials with their residuals and NEES, the prediction per path, and the
    calibration's verdict, parameters and covariance."""
    result = calibration.result
    verdict = tested.to_json_dict()
    verdict["parameter_uncertainty"] = (
        "included (delta method, the estimate's covariance)"
        if tested.parameter_uncertainty
        else "left out: the estimate's covariance is not finite"
    )
    predictions = {}
    for label, p in zip(measured.labels, predictions_of(measured, result), strict=True):
        if label not in predictions:
            predictions[label] = {"mean": p.mean.tolist(), "cov": p.cov.tolist()}
    rows = zip(
        measured.numbers,
        measured.labels,
        measured.poses,
        tested.residuals,
        tested.trial_nees,
        strict=True,
    )
    verdict["detectable"] = {
        name: {"error": d.shift, "power": d.power, "test": d.test}
        for name, d in detectable_by_name(tested, result).items()
    }
    return {
        "verdict": verdict,
        "path": vpath.text,
        "session": str(session),
        "validation_session": str(folder) if folder is not None else None,
        "source": measured.source,
        "n_trials": len(measured),
        "left_out_ambiguous": list(measured.left_out),
        "trials": [
            {
                "trial": n,
                "path": label,
                "pose_change": pose.tolist(),
                "residual": r.tolist(),
                "nees": float(e),
            }
            for n, label, pose, r, e in rows
        ],
        "prediction": predictions,
        "calibration": {
            "verdict": result.verdict.to_json_dict(),
            "parameters": {p.name: p.to_json_dict() for p in result.parameters},
            "covariance": [list(row) for row in result.covariance]
            if parameter_covariance(result) is not None
            else None,
        },
    }


def _file_measure(measure: str | None) -> bool:
    """Whether ``--measure`` names a trial file (of a square's measured poses)."""
    return measure is not None and isinstance(parse_measure(measure).settings, TrialFileSettings)
