"""A validation measured with the tape in the wizard: ``odohil wizard
--validate SESSION --path PATH --trials N``.

The operator validates as they calibrate: the wizard's pre-flight ticks, floor
marks before and after each trial, the tape's prompts with their re-measure
and typo checks, Ctrl-C (the robot stopped and the session journaled) and
resume by running the same command again. The trials are journaled as the
calibration's validation session, by default ``SESSION/validation/<path>/``
(odohil/session/results/validation.py), never mixed into its fit; after each solved
trial the wizard shows the test so far, and its final screen gives the
validation's verdict (exit 0 pass, 3 fail), as ``odohil validate`` does.

Why the wizard and not ``odohil validate --measure tape``: the wizard is the
command with an operator at the terminal (its prompts, its Ctrl-C and resume),
``validate`` the one a script runs (``--json``); a validation with the tape is
the wizard's work with another purpose.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from odohil import units
from odohil.errors import JournalError, MeasurementError, ParameterError
from odohil.science.validation import DEFAULT_ALPHA, ValidationResult
from odohil.session.commands.validate import calibration_robot, drive_folder
from odohil.session.commands.validate_power import Sizing, size_validation
from odohil.session.journal.events import OPERATOR
from odohil.session.journal.state import SessionState, load_session
from odohil.session.plans.plan import Plan
from odohil.session.results.validation import (
    PATH_SYNTAX,
    Calibration,
    ValidationPath,
    check_trials,
    check_turn_errors,
    default_folder,
    load_calibration,
    parse_validation_path,
    sensitivity_text,
    trials_of_session,
)
from odohil.session.run import SessionSpec
from odohil.session.text.outcome import DETECT_HELP

__all__ = [
    "DETECT_HELP",
    "GuidedValidation",
]


@dataclass(frozen=True)
class GuidedValidation:
    """A validation session the wizard drives, and the calibration it tests.

    Attributes:
        spec: the validation session to open (the operator's tape, purpose
            ``validate``, in ``SESSION/validation/<path>/`` or ``--session``).
        calibration: the calibration's outcome (its estimate and verdict).
        vpath: the path validated.
        session: the calibration session folder.
        alpha: the verdict's false-rejection level.
        sizing: the trial count ``--detect`` chose or checked (None without it,
            or when a validation is continued).
    """

    spec: SessionSpec
    calibration: Calibration
    vpath: ValidationPath
    session: Path
    alpha: float = DEFAULT_ALPHA
    sizing: Sizing | None = None

    def sizing_lines(self) -> list[str]:
        """The trial count ``--detect`` chose and each error's power (none without it)."""
        return [] if self.sizing is None else self.sizing.lines()

    @property
    def trusted(self) -> bool:
        """The calibration may be tested (a trusted estimate)."""
        result = self.calibration.outcome.result
        return result is not None and result.verdict.trusted

    @property
    def again(self) -> str:
        """The command that continues (or re-tests) this validation."""
        command = f"odohil wizard --validate {self.session} --path {self.vpath.text}"
        if self.spec.folder != default_folder(self.session, self.vpath):
            command += f" --session {self.spec.folder}"
        return command

    def tested(self, state: SessionState) -> ValidationResult:
        """The NEES and bias tests of the trials solved so far (an ambiguous
        trial is left out).

        Raises:
            MeasurementError: no usable trial yet.
        """
        trials = trials_of_session(state, source=str(self.spec.folder))
        return check_trials(trials, self.calibration.result, self.alpha)

    def live_line(self, state: SessionState) -> str:
        """The test so far, after a solved trial (one line)."""
        assert state.plan is not None
        try:
            tested = self.tested(state)
        except MeasurementError as exc:
            return f"Validation: nothing to test yet ({exc})"
        so_far = "failing" if not tested.passed else "passing"
        if len(state.completed) >= state.plan.n_trials:  # the last trial
            so_far = "failed" if not tested.passed else "passed"
        else:
            so_far += " so far"
        overall = tested.overall
        return (
            f"Validation after {units.plural(tested.n_trials, 'trial')} of "
            f"{state.plan.n_trials}: {so_far} (NEES {overall.statistic:.3g} on "
            f"{overall.dof} dof, threshold {overall.threshold:.3g})"
        )

    def final(self, state: SessionState) -> tuple[bool, tuple[str, ...]]:
        """The validation's verdict: (passed, its lines: the verdict, why it
        fails, where it is journaled and how to test it again). No usable trial
        is a failure to validate."""
        where = (
            f"journaled in {self.spec.folder}; `odohil validate {self.session} --path "
            f"{self.vpath.text}` tests it again, `odohil report {self.session}` shows it"
        )
        try:
            tested = self.tested(state)
        except MeasurementError as exc:
            return False, (f"validation: NOT TESTED ({exc})", where)
        status = "PASS" if tested.passed else "FAIL"
        failed = tested.failed()
        head = f"validation: {status} ({units.plural(tested.n_trials, 'trial')} of "
        head += f"{self.vpath.text}" + (f"; rejected by {', '.join(failed)})" if failed else ")")
        reasons = tuple(f"  {reason}" for reason in tested.reasons())
        sensitivity = sensitivity_text(tested, self.calibration.result)
        return tested.passed, (head, *reasons, sensitivity, where)


def guided_validation(
    session: Path,
    path_text: str,
    trials: int | None,
    *,
    folder: Path | None = None,
    robot_file: Path | None = None,
    port: str | None = None,
    baud: int | None = None,
    max_leg_m: float | None = None,
    note: Mapping[str, Any] | None = None,
    detect: str | None = None,
) -> GuidedValidation:
    """The wizard's validation of the calibration ``session`` on ``path_text``
    (``--path``), ``trials`` trials (None: a resumed validation's, or as many
    as ``detect`` (``--detect``) needs: odohil/session/commands/validate_power.py,
    measured with the tape), journaled in ``folder`` (default
    ``SESSION/validation/<path>/``); nothing is written, opened or moved.

    Raises:
        ParameterError: a path the wizard does not drive (``file:``), no
            ``--trials`` for a new validation, a path the calibration was
            fitted on, a path whose turns the calibration has no turn error
            for (odohil/session/results/validation.py ``check_turn_errors``),
            or a calibration that is no session.
        JournalError: the folder holds another path's validation, or the
            calibration's journal is corrupt.
        RobotDescriptionError: a ``--robot`` that cannot be used.
    """
    vpath = parse_validation_path(path_text)
    if vpath.drivable is None:
        raise ParameterError(
            f"--path {path_text}: the wizard drives the path with the tape; the trials of a "
            "file are tested by `odohil validate SESSION --path file:...`"
        )
    target = folder or default_folder(session, vpath)
    continued = (target / "journal.jsonl").is_file()
    if continued:
        journaled = load_session(target).state.header.settings.get("validation_path")
        if journaled != vpath.text:
            held = f"the validation of {journaled}" if journaled else "another session"
            raise JournalError(
                f"{target} holds {held}, not of --path {vpath.text}: give --session NEW_FOLDER"
            )
    elif trials is None and detect is None:
        raise ParameterError(
            "--trials N is needed to start a validation (N in 1..10000), or --detect "
            "NAME=VALUE to choose it"
        )
    calibration = load_calibration(session)
    drive_folder(vpath, calibration, session, target)  # a session, not fitted on the path
    robot = calibration_robot(calibration, robot_file)
    if calibration.outcome.result is not None and vpath.path is not None:
        check_turn_errors(  # as odohil validate
            [vpath.path], calibration.outcome.result, robot.description.robot.turns_exact,
            f"--path {path_text}",
        )  # fmt: skip
    sizing = None
    if detect is not None and not continued and calibration.outcome.result is not None:
        sizing = size_validation(
            detect, vpath, calibration.outcome.result, robot.description, measure=None,
            trials=trials, alpha=DEFAULT_ALPHA,
        )  # fmt: skip
        trials = sizing.trials
    plan: Plan | None = None if trials is None else Plan.of([(vpath.drivable, trials)])
    spec = SessionSpec(
        target,
        "auto",
        Path(robot.path) if robot.path else None,
        robot_toml=robot.toml,
        plan=plan,
        measure=OPERATOR,
        port=port,
        baud=baud,
        purpose="validate",
        max_leg_m=max_leg_m,
        allow_few_trials=True,
        settings={"validation_of": str(session.resolve()), "validation_path": vpath.text},
        note=dict(note or {}),
        calibration=calibration.outcome.result,
    )
    return GuidedValidation(spec, calibration, vpath, session, sizing=sizing)


def validation_of(folder: Path) -> tuple[Path, str] | None:
    """The calibration session and the ``--path`` of the validation session
    journaled in ``folder`` (the wizard given only ``--session`` continues it
    as a validation), or None when ``folder`` holds no validation session.

    A journal that cannot be read is left to the pre-flight's session check.
    """
    if not (folder / "journal.jsonl").is_file():
        return None
    try:
        settings = load_session(folder).state.header.settings
    except JournalError:
        return None
    of, path = settings.get("validation_of"), settings.get("validation_path")
    if not (isinstance(of, str) and isinstance(path, str) and of and path):
        return None
    return Path(of), path


def validation_target(
    validate: Path | None, path_text: str | None, trials: int | None, session: Path | None
) -> tuple[Path, str] | None:
    """What the wizard validates: the calibration session and ``--path`` of
    ``--validate SESSION --path PATH``, or of the validation session that
    ``--session`` names (continued as one); None: the wizard calibrates.

    Raises:
        ParameterError: ``--validate`` without ``--path``, or ``--path`` or
            ``--trials`` without ``--validate`` (and no validation session).
    """
    if validate is not None:
        if path_text is None:
            raise ParameterError(
                f"--validate {validate}: give the path to validate on, --path PATH ({PATH_SYNTAX})"
            )
        return validate, path_text
    found = validation_of(session) if session is not None else None
    if found is None:
        if path_text is not None or trials is not None:
            raise ParameterError(
                "--path and --trials name a validation: give --validate SESSION (the "
                "calibrated session) too; a calibration's plan is --plan"
            )
        return None
    return found[0], path_text or found[1]
