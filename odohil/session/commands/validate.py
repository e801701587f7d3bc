"""What ``odohil validate`` decides before it drives a validation path
(odohil/session/commands/validate_steps.py for the parts): what it tests (the path,
the calibration and the robot description: :func:`validation_setup`), the
options a trial file does not use, the finished validation session it tests
again without driving, the session spec of one it drives, and the held-out
trials it tests (:func:`held_out`), read from a file or driven by the
caller; and the lines that tell the verdict (:func:`verdict_lines`,
:func:`chi_square_table`)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from odohil import units
from odohil.errors import JournalError, ParameterError
from odohil.science.estimators import EstimateResult
from odohil.science.validation import ValidationResult
from odohil.session.commands.validate_steps import (
    CalibrationRobot,
    calibration_robot,
    check_alpha,
    drive_folder,
    drives,
    first_trials,
    measured_trials,
)
from odohil.session.journal.state import load_session
from odohil.session.plans.plan import Plan
from odohil.session.results.validation import (
    Calibration,
    ValidationPath,
    ValidationTrials,
    load_calibration,
    parse_validation_path,
    sensitivity_text,
    trials_of_session,
)
from odohil.session.robots.description import load_robot_description
from odohil.session.run import SessionSpec
from odohil.session.table_text import TableText
from odohil.session.trials.logs import ImportOptions


@dataclass(frozen=True)
class ValidationSetup:
    """What a validation tests.

    Attributes:
        vpath: the path (``--path``).
        calibration: the calibration's outcome and, for a session, its state.
        robot: the robot description the held-out trials are read or driven with.
    """

    vpath: ValidationPath
    calibration: Calibration
    robot: CalibrationRobot


def validation_setup(
    session: Path,
    path_text: str,
    robot_file: Path | None,
    exclude: frozenset[int],
    recording: ImportOptions,
    alpha: float,
) -> ValidationSetup:
    """``--alpha`` and ``--path`` checked, the calibration ``session`` (a
    session, a trial file or a recording) estimated without ``exclude``, and
    the robot description (``--robot``'s, else the session's); before anything moves.

    Raises:
        ParameterError, RobotDescriptionError, JournalError, MeasurementError,
            OSError: bad input.
    """
    check_alpha(alpha)
    vpath = parse_validation_path(path_text)
    given = None if robot_file is None else load_robot_description(robot_file)
    calibration = load_calibration(session, exclude, given, recording)
    return ValidationSetup(vpath, calibration, calibration_robot(calibration, robot_file))


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
) -> SessionSpec:
    """The session that drives ``trials`` of ``vpath`` into ``folder`` with
    ``measure`` as a validation of the calibration ``session``, with
    ``robot``'s description (the line and the seed: the spec's defaults); its
    trials predicted under ``calibration``, the calibration's estimate.

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
        settings={"validation_of": str(session.resolve()), "validation_path": vpath.text},
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
    """

    measured: ValidationTrials
    folder: Path | None = None
    reread: bool = False


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
    ``drive`` (a new validation session's spec in, its trials out). Of driven
    trials the first ``trials``: one the tape found ambiguous is left out, not redone.

    Raises:
        ParameterError, JournalError, MeasurementError, OSError: bad input (nothing moved).
    """
    vpath, calibration, robot = setup.vpath, setup.calibration, setup.robot
    check_file_options(vpath, port, measure)
    if not drives(vpath, port, measure):
        measured = measured_trials(vpath, calibration, robot.description, recording, port, measure)
        return HeldOut(first_trials(measured, trials))
    folder = drive_folder(vpath, calibration, session, out)
    journaled = journaled_trials(folder, vpath)
    if journaled is None:
        result = calibration.outcome.result
        spec = validation_spec(folder, vpath, session, robot, trials, measure, calibration=result)
        measured = drive(spec)
    else:
        measured = journaled
    taken = first_trials(measured, min(trials or len(measured), len(measured)))
    return HeldOut(taken, folder, reread=journaled is not None)


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
