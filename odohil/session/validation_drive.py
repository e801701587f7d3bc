"""What ``odohil validate`` decides before it drives a validation path
(odohil/session/validation_steps.py for the rest): the options a trial file
does not use, the finished validation session it tests again without
driving, and the session spec of one it drives."""

from __future__ import annotations

from pathlib import Path

from odohil.errors import JournalError, ParameterError
from odohil.science.estimators import EstimateResult
from odohil.session.lifecycle import SessionSpec
from odohil.session.plan import Plan
from odohil.session.state import load_session
from odohil.session.validation import ValidationPath, ValidationTrials, trials_of_session
from odohil.session.validation_steps import CalibrationRobot


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
