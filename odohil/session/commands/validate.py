"""What ``odohil validate`` decides before it drives a validation path: what
it tests (the path, the calibration and the robot description: :func:`validation_setup`), the
options a trial file does not use, the finished validation session it tests
again without driving, the session spec of one it drives, and the held-out
trials it tests (:func:`held_out`), read from a file or driven by the
caller; and the lines that tell the verdict (:func:`verdict_lines`,
:func:`chi_square_table`).

It also computes what the command needs besides driving: the robot description the
held-out trials are read with, the held-out trials of a file or a measured
square, the first N of them, and the result as its JSON document.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from odohil import units
from odohil.errors import JournalError, ParameterError
from odohil.science.estimators import EstimateResult
from odohil.science.robot_description import RobotDescription
from odohil.science.validation import DEFAULT_ALPHA, ValidationResult
from odohil.session.commands.validate_power import Sizing, parse_detect, size_validation
from odohil.session.journal.state import description_of_header, load_session
from odohil.session.measure.kinds import TrialFileSettings
from odohil.session.measure.registry import parse_measure
from odohil.session.plans.plan import Plan
from odohil.session.results.validation import (
    Calibration,
    ValidationPath,
    ValidationTrials,
    check_not_fitted,
    check_turn_errors,
    default_folder,
    detectable_by_name,
    held_out_trials,
    load_calibration,
    parameter_covariance,
    parse_validation_path,
    predictions_of,
    read_path_poses,
    sensitivity_text,
    trials_of_session,
)
from odohil.session.robots.description import load_robot_description, read_robot_toml
from odohil.session.robots.registry import parse_description as parse_robot_description
from odohil.session.run import SessionSpec
from odohil.session.table_text import TableText
from odohil.session.trials.logs import ImportOptions

__all__ = [
    "calibration_robot",
    "chi_square_table",
    "drive_folder",
    "held_out",
    "lines_below_tests",
    "validation_document",
    "validation_setup",
    "verdict_lines",
]


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
        if calibration.outcome.result is not None:
            check_turn_errors(
                measured.paths, calibration.outcome.result, description.robot.turns_exact,
                f"--path {vpath.text}",
            )  # fmt: skip
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
    sizing: Sizing | None = None,
) -> dict[str, Any]:
    """The JSON document of ``odohil validate --json`` (SI): the verdict, the
    trials with their residuals and NEES, the prediction per path, the
    calibration's verdict, parameters and covariance, and with ``--detect``
    the sizing of the trials driven."""
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
        **({} if sizing is None else {"sizing": sizing.to_json_dict()}),
        "path": vpath.text,
        "session": str(session),
        "validation_session": str(folder) if folder is not None else None,
        "source": measured.source,
        "n_trials": len(measured),
        "left_out_ambiguous": list(measured.left_out),
        **({} if measured.windows is None else {"windows": measured.windows.to_json_dict()}),
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


@dataclass(frozen=True)
class ValidationSetup:
    """What a validation tests.

    Attributes:
        vpath: the path (``--path``).
        calibration: the calibration's outcome and, for a session, its state.
        robot: the robot description the held-out trials are read or driven with.
        detect: ``--detect``, the error the driven trials are sized to catch
            (odohil/session/commands/validate_power.py), or None.
        alpha: the verdict's false-rejection level (``--alpha``).
    """

    vpath: ValidationPath
    calibration: Calibration
    robot: CalibrationRobot
    detect: str | None = None
    alpha: float = DEFAULT_ALPHA


def validation_setup(
    session: Path,
    path_text: str,
    robot_file: Path | None,
    exclude: frozenset[int],
    recording: ImportOptions,
    alpha: float,
    detect: str | None = None,
) -> ValidationSetup:
    """``--alpha`` and ``--path`` checked, the calibration ``session`` (a
    session, a trial file or a recording) estimated without ``exclude``, and
    the robot description (``--robot``'s, else the session's); a path whose
    turns the calibration has no turn error for refused (:func:`check_turn_errors`);
    before anything moves.

    Raises:
        ParameterError, RobotDescriptionError, JournalError, MeasurementError,
            OSError: bad input.
    """
    check_alpha(alpha)
    vpath = parse_validation_path(path_text)
    given = None if robot_file is None else load_robot_description(robot_file)
    calibration = load_calibration(session, exclude, given, recording)
    robot = calibration_robot(calibration, robot_file)
    result = calibration.outcome.result
    if result is not None and vpath.path is not None:  # a file's paths: held_out
        check_turn_errors(
            [vpath.path], result, robot.description.robot.turns_exact, f"--path {vpath.text}"
        )
    if detect is not None and result is not None:  # checked before anything moves
        parse_detect(detect, tuple(p.name for p in result.parameters))
    return ValidationSetup(vpath, calibration, robot, detect, alpha)


def check_file_options(vpath: ValidationPath, port: str | None, measure: str | None) -> None:
    """``--path file:HELDOUT`` reads its trials from the file: no robot.

    Raises:
        ParameterError: ``--port`` or ``--measure`` given with a file.
    """
    if vpath.kind == "file" and (port is not None or measure is not None):
        raise ParameterError(
            f"--path {vpath.text} reads its trials from the file: --port and --measure "
            "are not used (to drive, give --path forth-back:K,L or square:SIDE)"
        )


def journaled_trials(folder: Path, vpath: ValidationPath) -> ValidationTrials | None:
    """The trials of the finished validation of ``vpath`` journaled in
    ``folder`` (tested again, nothing driven); None when ``folder`` holds no
    session journal yet.

    Raises:
        JournalError: ``folder`` holds another path's validation or an
            unfinished one (give another ``--out``, or resume it first).
    """
    if not (folder / "journal.jsonl").is_file():
        return None
    state = load_session(folder).state
    settings = state.header.get("settings", {})
    if settings.get("validation_path") != vpath.text or not state.finished:
        raise JournalError(
            f"{folder} holds {'another' if state.finished else 'an unfinished'} "
            "validation session: give --out NEW_FOLDER"
            + ("" if state.finished else f", or `odohil resume {folder}` first")
        )
    return trials_of_session(state, source=str(folder))


def validation_spec(
    folder: Path,
    vpath: ValidationPath,
    session: Path,
    robot: CalibrationRobot,
    trials: int | None,
    measure: str | None,
    *,
    calibration: EstimateResult | None = None,
    sizing: Sizing | None = None,
) -> SessionSpec:
    """The session that drives ``trials`` of ``vpath`` into ``folder`` with
    ``measure`` as a validation of the calibration ``session``, with
    ``robot``'s description (the line and the seed: the spec's defaults); its
    trials predicted under ``calibration``, the calibration's estimate; the
    ``sizing`` of ``--detect`` journaled in its settings.

    Raises:
        ParameterError: no ``--trials`` or no ``--measure``.
    """
    drivable = vpath.drivable
    assert drivable is not None
    if trials is None:
        raise ParameterError("--trials N is needed to drive a validation path (N in 1..10000)")
    if measure is None:
        raise ParameterError(
            "--measure is needed to drive: `fake`, `tcp://HOST:PORT` or a trial file (CSV)"
        )
    return SessionSpec(
        folder,
        "new",
        Path(robot.path) if robot.path else None,
        robot_toml=robot.toml,
        plan=Plan.of([(drivable, trials)]),
        measure=measure,
        purpose="validate",
        settings={"validation_of": str(session.resolve()), "validation_path": vpath.text}
        | ({} if sizing is None else {"sizing": sizing.to_json_dict()}),
        calibration=calibration,
    )


@dataclass(frozen=True)
class HeldOut:
    """The held-out trials a validation tests.

    Attributes:
        measured: the trials.
        folder: the validation session they are journaled in (None: read
            from a file, nothing driven).
        reread: the trials of a finished validation journaled in ``folder``,
            tested again without driving.
        sizing: the trial count ``--detect`` chose for the trials driven, or None.
    """

    measured: ValidationTrials
    folder: Path | None = None
    reread: bool = False
    sizing: Sizing | None = None


def held_out(
    setup: ValidationSetup,
    session: Path,
    recording: ImportOptions,
    drive: Callable[[SessionSpec], ValidationTrials],
    *,
    trials: int | None,
    measure: str | None,
    port: str | None,
    out: Path | None,
) -> HeldOut:
    """The held-out trials of ``setup``: read from ``--path file:HELDOUT`` or
    a general path's pose file (the first ``trials``); else those journaled in
    the validation folder (``out``, else SESSION/validation/<path>/), tested
    again when it holds a finished validation of the path, else driven by
    ``drive`` (a new validation session's spec in, its trials out), as many
    as ``setup.detect`` needs when given (:func:`size_validation`, before the
    spec). Of driven trials the first ``trials``: one the tape found
    ambiguous is left out, not redone.

    Raises:
        ParameterError, JournalError, MeasurementError, OSError: bad input (nothing moved).
    """
    vpath, calibration, robot = setup.vpath, setup.calibration, setup.robot
    check_file_options(vpath, port, measure)
    if setup.detect is not None and not drives(vpath, port, measure):
        raise ParameterError(
            f"--detect sizes the trials a validation drives; the trials of --path {vpath.text} "
            "are given (what a pass rules out is printed with the verdict)"
        )
    if not drives(vpath, port, measure):
        measured = measured_trials(vpath, calibration, robot.description, recording, port, measure)
        return HeldOut(first_trials(measured, trials))
    folder = drive_folder(vpath, calibration, session, out)
    journaled = journaled_trials(folder, vpath)
    sizing = None
    if journaled is None:
        result = calibration.result
        if setup.detect is not None:
            sizing = size_validation(
                setup.detect, vpath, result, robot.description, measure=measure, trials=trials,
                alpha=setup.alpha,
            )  # fmt: skip
            trials = sizing.trials
        spec = validation_spec(
            folder, vpath, session, robot, trials, measure, calibration=result, sizing=sizing
        )
        measured = drive(spec)
    else:
        measured = journaled
    taken = first_trials(measured, min(trials or len(measured), len(measured)))
    return HeldOut(taken, folder, reread=journaled is not None, sizing=sizing)


def verdict_lines(
    tested: ValidationResult, path: str, calibration: EstimateResult | None = None
) -> list[str]:
    """``validation: PASS (8 trials of square:1,cw)`` (``FAIL``, naming the
    tests that rejected), then why, a line a failed kind of test; with the
    ``calibration`` tested, what a pass rules out (:func:`sensitivity_text`)."""
    status = "PASS" if tested.passed else "FAIL"
    failed = tested.failed()
    text = f"validation: {status} ({units.plural(tested.n_trials, 'trial')} of {path}"
    text += f"; rejected by {', '.join(failed)})" if failed else ")"
    lines = [text, *(f"  {reason}" for reason in tested.reasons())]
    if calibration is not None:
        lines.append(sensitivity_text(tested, calibration))
    return lines


def lines_below_tests(measured: ValidationTrials, uncertainty: str) -> list[str]:
    """What is printed below the tests: how the calibration's ``uncertainty``
    was taken (the verdict's ``parameter_uncertainty``), the held-out trials
    left out as ambiguous, and how a held-out continuous log's windows went."""
    lines = [f"parameter uncertainty: {uncertainty}"]
    if measured.left_out:
        lines.append(f"ambiguous trials left out: {', '.join(map(str, measured.left_out))}")
    if measured.windows is not None:
        head, *named = measured.windows.lines()
        lines += [f"held-out {head}", *named]
    return lines


def chi_square_table(tested: ValidationResult) -> TableText:
    """The table of the chi-square tests, each ``pass`` or ``FAIL``."""
    title = "chi-square tests (NEES: the spread; bias: the mean residual), each at level"
    rows: list[tuple[str, ...]] = [
        (
            t.name,
            f"{t.statistic:.4g}",
            str(t.dof),
            f"{t.p_value:.3g}",
            f"{t.threshold:.4g}",
            "pass" if t.passed else "FAIL",
        )
        for t in tested.tests
    ]
    columns = ("test", "statistic", "dof", "p-value", "threshold", "result")
    title = f"{title} {tested.level:g}"
    return TableText(title, columns, rows, ("test", "result"), flagged=("FAIL",))
