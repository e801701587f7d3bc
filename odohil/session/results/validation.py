"""Validation of a calibrated session on a path it was not fitted on.

The calibrated model is the session's estimate, computed as ``odohil
estimate SESSION`` computes it (robust maximum likelihood over the solved,
unambiguous trials). The validation trials come from:

- a validation session driven by the engine (a forth-and-back design), in its
  own folder, by default ``SESSION/validation/<path>/`` (:func:`default_folder`):
  a session like any other whose header's ``settings`` name the calibration
  (``validation_of``) and the path (``validation_path``). The calibration's
  journal never sees these trials, so they are never mixed into its fit;
- a trial file in the existing format (``--path file:CSV``,
  odohil/session/trials/trial_file.py), its rows naming their designs;
- a validation session of a general path (``--path square:SIDE[,cw|ccw]``,
  ``polygon:N,SIDE[,cw|ccw]``, ``circle:RADIUS,N[,cw|ccw]``;
  odohil/science/path_designs.py) driven by the engine likewise, in
  ``SESSION/validation/<slug>/``;
- a file of pose changes for such a path, driven by another program
  (``--path square:SIDE --measure FILE``, no ``--port``): columns
  ``dx_m,dy_m,dtheta_rad`` and optionally ``sigma_x_m,sigma_y_m,sigma_theta_rad``
  (measurement standard deviations; 0 when absent).

The test itself is :func:`odohil.science.validation.validation_test`.
"""

from __future__ import annotations

import math
from collections.abc import Collection, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Literal

import numpy as np

from odohil.errors import (
    JournalError,
    MeasurementError,
    OdohilError,
    ParameterError,
)
from odohil.science.estimators import EstimateResult
from odohil.science.limits import RANGES
from odohil.science.moments import turn_errors_from
from odohil.science.parameters import PARAMETER_NAMES
from odohil.science.path_designs import PATH_KINDS, PathDesign, parse_path_design
from odohil.science.path_trials import PathTrial
from odohil.science.paths import TURN_CLASSES, Design, EncoderPath, FloatArray, Variant
from odohil.science.robot_description import RobotDescription
from odohil.science.validation import (
    DEFAULT_ALPHA,
    Detectable,
    EllipseData,
    PathPrediction,
    ValidationResult,
    ellipse_data,
    predict_fitted,
    predict_path,
    validation_test,
)
from odohil.session.journal.state import (
    SessionState,
    load_session,
    session_path_trials,
    session_trials,
)
from odohil.session.plans.plan import Plan
from odohil.session.results.outcome import (
    EstimateOutcome,
    estimate_source,
    estimate_state,
    load_path_cut,
    source_kind,
)
from odohil.session.trials.logs import ImportOptions, WindowCount
from odohil.session.trials.pose_file import (
    file_format,
    read_path_rows,
    read_pose_file,
    refuse_rows,
    steps_problem,
)
from odohil.session.trials.trial_file import TrialSet, read_trials
from odohil.units import paper_text

__all__ = [
    "PATH_SYNTAX",
    "VARIANCE_RATES",
    "Calibration",
    "ValidationPath",
    "ValidationTrials",
    "check_not_fitted",
    "check_trials",
    "check_turn_errors",
    "default_folder",
    "detectable_by_name",
    "held_out_trials",
    "load_calibration",
    "parameter_covariance",
    "parameter_dofs",
    "parse_validation_path",
    "predict_calibrated",
    "predictions_of",
    "read_path_poses",
    "sensitivity_text",
    "trials_of_session",
]

VALIDATION_FOLDER = "validation"
"""Sub-folder of a calibration session that holds its validation sessions."""
PATH_SYNTAX = (
    "square:SIDE[,cw|ccw], polygon:N,SIDE[,cw|ccw], circle:RADIUS,N[,cw|ccw], "
    "forth-back:K,L[,turn|reverse] or file:CSV"
)

PathKind = Literal["path", "forth-back", "file"]


@dataclass(frozen=True)
class ValidationPath:
    """What ``--path`` names.

    Attributes:
        kind: ``path`` (a square, polygon or circle), ``forth-back`` or ``file``.
        text: the option's text.
        design: the forth-and-back design (``forth-back``), else None.
        path: the encoder path (``path`` and ``forth-back``), else None.
        file: the trial file (``file``), else None.
        shape: the general path (``path``), else None.
    """

    kind: PathKind
    text: str
    design: Design | None = None
    path: EncoderPath | None = None
    file: Path | None = None
    shape: PathDesign | None = None

    @property
    def drivable(self) -> Design | PathDesign | None:
        """What a validation session drives: the design or the general path
        (None for a file)."""
        return self.design if self.design is not None else self.shape

    def slug(self) -> str:
        """A folder name for it, e.g. ``forth-back-k2-l1.5-turn``, ``square-2-ccw``."""
        if self.design is not None:
            d = self.design
            return f"forth-back-k{d.k:g}-l{d.l_m:g}-{d.variant}"
        if self.shape is not None:
            return self.shape.slug()
        return "file-" + (self.file.stem if self.file is not None else "trials")


def parse_validation_path(text: str) -> ValidationPath:
    """Parse ``--path``.

    Raises:
        ParameterError: naming ``--path``, the accepted forms and ranges.
    """
    kind, _, rest = text.strip().partition(":")
    kind = kind.strip().lower()
    if kind in PATH_KINDS and kind != "square":
        try:
            shape = parse_path_design(text)
        except ParameterError as exc:  # it names the text and the accepted paths
            raise ParameterError(f"--path {exc}; or forth-back:K,L or file:CSV") from None
        return ValidationPath("path", text, path=shape.path(), shape=shape)
    try:
        if kind == "square":
            # the side's range named as the option gives it, then the rest
            RANGES["side"].check("SIDE", _number(rest.partition(",")[0], "SIDE"))
            shape = parse_path_design(text)
            return ValidationPath("path", text, path=shape.path(), shape=shape)
        if kind in ("forth-back", "forth-and-back"):
            parts = [p.strip() for p in rest.split(",")]
            if len(parts) not in (2, 3):
                raise ParameterError("give K,L or K,L,VARIANT (e.g. forth-back:2,1.5)")
            variant: Variant = "turn"
            if len(parts) == 3:
                if parts[2] not in ("turn", "reverse"):
                    raise ParameterError(f"VARIANT must be turn or reverse, got {parts[2]!r}")
                variant = "reverse" if parts[2] == "reverse" else "turn"
            design = Design(_number(parts[0], "K"), _number(parts[1], "L"), variant)
            return ValidationPath("forth-back", text, design=design, path=design.path())
        if kind == "file":
            if not rest.strip():
                raise ParameterError("give the trial file, e.g. file:validation.csv")
            return ValidationPath("file", text, file=Path(rest.strip()))
    except ParameterError as exc:
        raise ParameterError(f"--path {text!r}: {exc} (accepted: {PATH_SYNTAX})") from None
    raise ParameterError(f"--path {text!r}: unknown path; accepted: {PATH_SYNTAX}")


def _number(text: str, name: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise ParameterError(f"{name} must be a number, got {text!r}") from None
    if not math.isfinite(value):
        raise ParameterError(f"{name} must be finite, got {text!r}")
    return value


def default_folder(session: Path, path: ValidationPath) -> Path:
    """``SESSION/validation/<path slug>``."""
    return session / VALIDATION_FOLDER / path.slug()


@dataclass(frozen=True)
class Calibration:
    """A calibration session's estimate, as ``odohil estimate SESSION`` makes it
    (odohil/session/results/outcome.py).

    Attributes:
        outcome: the recipe's outcome: the estimate (robust maximum
            likelihood) and its verdict, or why there is none.
        state: the session as its journal tells it (None for a trial file or
            a recording).
    """

    outcome: EstimateOutcome
    state: SessionState | None = None

    @property
    def result(self) -> EstimateResult:
        """The estimate.

        Raises:
            MeasurementError: the trials give none (the outcome says why).
        """
        if self.outcome.result is None:
            raise MeasurementError(self.outcome.problem)
        return self.outcome.result


def load_calibration(
    source: Path,
    exclude: Collection[int] = (),
    description: RobotDescription | None = None,
    recording: ImportOptions | None = None,
) -> Calibration:
    """The calibration's outcome (every solved trial but the ambiguous ones and
    ``exclude``), through the one loader (odohil/session/results/outcome.py): a session
    folder, a trial file (forth-and-back or general-path) or a recording
    (``description`` required; it gives ``turns_exact`` to files too).

    Raises:
        JournalError: a validation session, or a corrupt journal.
        ParameterError: a recording without ``description``.
        TrialFileError, RecordingError: the file cannot be used.
        MeasurementError: an excluded number that is no trial's.
    """
    if source_kind([source], recording) != "session":
        outcome = estimate_source([source], description, exclude, recording=recording)
        return Calibration(outcome, None)
    state = load_session(source).state
    if state.header.settings.get("validation_of"):
        raise JournalError(
            f"{source} is a validation session; give the calibration session it validates"
        )
    return Calibration(estimate_state(state, exclude, source=str(source)), state)


def check_not_fitted(plan: Plan | None, designs: Sequence[Design | PathDesign]) -> None:
    """A validation design must not be one the calibration was fitted on.

    Raises:
        ParameterError: naming the design.
    """
    if plan is None:
        return
    fitted = {(d.k, d.l_m, d.variant) for d, _ in plan.line_items}
    paths = {item.design for item in plan.items if isinstance(item.design, PathDesign)}
    for design in designs:
        if isinstance(design, PathDesign):
            if design in paths:
                raise ParameterError(
                    f"--path: {design.label()} is a path of the calibration's plan; "
                    "validate on a path the fit did not use"
                )
            continue
        if (design.k, design.l_m, design.variant) in fitted:
            raise ParameterError(
                f"--path: {design.forward.label()} is a design of the calibration's plan; "
                "validate on a path the fit did not use"
            )


TURN_PLAN = (
    "k=1,l=2,n=10,variant=reverse;k=0.5,l=2,n=10,variant=reverse;"
    "path=polygon:3,0.5,cw,n=10;path=polygon:3,0.5,ccw,n=10"
)
"""A calibration plan that fits the turn errors: straight runs and triangles both ways."""


def check_turn_errors(
    paths: Sequence[EncoderPath], calibration: EstimateResult, turns_exact: bool, option: str
) -> None:
    """A path that turns in a way no turn error of the calibration covers
    is refused on a robot whose turns are not exact (``turns_exact = false``):
    the prediction would miss every turn's error, so a right calibration fails
    (a Create 2 calibrated on ``reverse`` designs only, then a square: a
    heading bias of -4 deg, z -7). One check, before anything moves or is
    tested: ``odohil validate`` (driven, pose files, trial files) and the
    wizard's validation.

    Raises:
        ParameterError: naming ``option``, the turns without a turn error and
            how to calibrate them.
    """
    if turns_exact:
        return
    turned = np.zeros(len(TURN_CLASSES))
    for path in paths:
        turned += path.turns.total_abs_rad
    names = [p.name for p in calibration.parameters]
    covered = turn_errors_from(names, [1.0] * len(names)).scales != 0.0
    missing = [c for row, c in enumerate(TURN_CLASSES) if turned[row] > 0 and not covered[row]]
    if not missing:
        return
    kinds = " and ".join(
        words
        for kind, words in (("spin", "turns in place"), ("arc", "arcs"))
        if any(c.startswith(kind) for c in missing)
    )
    fitted = [n for n in names if n.startswith("e_turn") or n == "K_spin"]
    has = (
        f"its turn errors ({', '.join(fitted)}) cover none of them"
        if fitted
        else "it has no e_turn, no K_spin (only a plan with squares or polygons fits them)"
    )
    raise ParameterError(
        f"{option}: this robot's turns are not exact (turns_exact = false) and the path makes "
        f"{kinds} ({', '.join(missing)}), but the calibration estimated no turn error for "
        f"them: {has}. Its prediction would miss each turn's error, so even a right "
        "calibration would fail. Calibrate with squares or triangles both ways beside the "
        f'straight runs (e.g. --plan "{TURN_PLAN}", or path=square:0.5,cw,n=10;'
        "path=square:0.5,ccw,n=10), or validate on a path without turns "
        "(forth-back:K,L,reverse). Nothing was driven or tested."
    )


@dataclass(frozen=True)
class ValidationTrials:
    """Measured validation trials and the paths they drove.

    Attributes:
        poses: (n, 3) measured pose changes (x m, y m, Delta rad).
        covs: (n, 3, 3) their measurement covariances (zeros: exact poses).
        paths: the encoder path of each trial.
        labels: a name for each trial's path (e.g. ``k=2 l=1.5 m turn``).
        numbers: each trial's number (session trial number or file row).
        backward: each trial was driven backwards (a one-way design's mirror).
        designs: each trial's design as driven (trial files and sessions; empty
            for a pose file of a named path).
        left_out: trials not tested (ambiguous), by number.
        source: where they came from.
        windows: how a continuous log's windows went (``--window-m``), else None.
    """

    poses: FloatArray
    covs: FloatArray
    paths: tuple[EncoderPath, ...]
    labels: tuple[str, ...]
    numbers: tuple[int, ...]
    backward: tuple[bool, ...]
    designs: tuple[Design, ...] = ()
    left_out: tuple[int, ...] = ()
    source: str = ""
    windows: WindowCount | None = None

    def __len__(self) -> int:
        return int(self.poses.shape[0])

    def first(self, n: int) -> ValidationTrials:
        """The first ``n`` trials."""
        return ValidationTrials(
            self.poses[:n],
            self.covs[:n],
            self.paths[:n],
            self.labels[:n],
            self.numbers[:n],
            self.backward[:n],
            self.designs[:n],
            self.left_out,
            self.source,
        )


def _from_trial_set(trials: TrialSet) -> ValidationTrials:
    rows = trials.trials
    if not rows:
        raise MeasurementError(f"{trials.source}: no usable trials")
    poses = np.array([t.pose_change for t in rows], dtype=np.float64)
    covs = np.array(
        [t.pose_cov if t.pose_cov is not None else np.zeros((3, 3)) for t in rows],
        dtype=np.float64,
    )
    return ValidationTrials(
        poses=poses,
        covs=covs,
        paths=tuple(t.design.path() for t in rows),
        labels=tuple(t.design.forward.label() for t in rows),
        numbers=tuple(t.number if t.number is not None else i + 1 for i, t in enumerate(rows)),
        backward=tuple(t.design.backward for t in rows),
        designs=tuple(t.design for t in rows),
        left_out=tuple(t.number or 0 for t in trials.ambiguous),
        source=trials.source,
    )


def trials_of_session(state: SessionState, source: str = "session") -> ValidationTrials:
    """The solved, unambiguous trials of a (validation) session, with the
    floor-mark solver's covariance as measurement covariance (a session of
    general paths: each trial's own path, labelled by its design)."""
    if state.plan is not None and state.plan.has_paths:
        trials = session_path_trials(state, source=source)
        out = trials_of_paths(trials, source)
        labels = tuple(t.design.label() for t in state.completed if not t.ambiguous)
        left_out = tuple(t.trial for t in state.completed if t.ambiguous)
        return replace(out, labels=labels, left_out=left_out)
    return _from_trial_set(session_trials(state, source=source))


def trials_of_file(path: Path, description: RobotDescription | None) -> ValidationTrials:
    """The trials of a trial file (poses, or raw distances with ``description``).

    Raises:
        TrialFileError: the file cannot be used (every bad row listed).
    """
    return _from_trial_set(read_trials(path, description))


def trials_of_paths(
    trials: Sequence[PathTrial], source: str, windows: WindowCount | None = None
) -> ValidationTrials:
    """General-path trials (a general-path trial file, a recording) as
    validation trials: their own paths, measured pose changes and covariances,
    labelled by family and direction; ``windows``: how a continuous log's
    windows went."""
    if not trials:
        raise MeasurementError(f"{source}: no usable trials")
    return ValidationTrials(
        poses=np.array([t.pose_change for t in trials], dtype=np.float64),
        covs=np.array([t.measurement_cov for t in trials], dtype=np.float64),
        paths=tuple(t.path for t in trials),
        labels=tuple(f"{t.family} {t.direction}" for t in trials),
        numbers=tuple(t.trial if t.trial is not None else i + 1 for i, t in enumerate(trials)),
        backward=(False,) * len(trials),
        source=source,
        windows=windows,
    )


def held_out_trials(
    path: Path,
    description: RobotDescription | None,
    recording: ImportOptions | None = None,
) -> ValidationTrials:
    """The held-out trials of ``--path file:PATH``: a forth-and-back trial file
    (poses, or raw distances with ``description``), a general-path trial file
    or a recording (``description`` required), through the one loader.

    Raises:
        ParameterError: a session folder, or a recording without ``description``.
        TrialFileError, RecordingError: the file cannot be used.
    """
    kind = source_kind([path], recording)
    if kind == "session":
        raise ParameterError(
            f"--path file:{path}: a session folder; give a trial file or a recording"
        )
    if kind == "trials":
        return trials_of_file(path, description)
    cut = load_path_cut([path], description, recording)
    return trials_of_paths(cut.trials, str(path), cut.windows)


def read_path_poses(file: Path, path: EncoderPath, label: str) -> ValidationTrials:
    """Pose changes of trials of ``path`` from a CSV with the columns
    ``dx_m,dy_m,dtheta_rad`` and optionally ``sigma_x_m,sigma_y_m,sigma_theta_rad``
    (blank lines and ``#`` comments ignored), or from a general-path trial file
    whose every row is of ``path`` (odohil/session/trials/pose_file.py).

    Raises:
        TrialFileError: naming the file, the line and the column, or the rows
            of another path.
    """
    if file_format(file) == "path-trials":
        rows = read_path_rows(file)
        wrong = [
            f"row {row.number} (line {row.line}): {problem}"
            for row in rows
            if (problem := steps_problem(row, path, label))
        ]
        refuse_rows(file, wrong, "path")
    else:
        rows = read_pose_file(file, f"--path {label}")
    n = len(rows)
    return ValidationTrials(
        poses=np.array([row.pose for row in rows], dtype=np.float64),
        covs=np.array(
            [row.cov if row.cov is not None else np.zeros((3, 3)) for row in rows],
            dtype=np.float64,
        ),
        paths=(path,) * n,
        labels=(label,) * n,
        numbers=tuple(row.number for row in rows),
        backward=(False,) * n,
        source=str(file),
    )


def predictions_of(trials: ValidationTrials, calibration: EstimateResult) -> list[PathPrediction]:
    """Each trial's prediction at the calibration's parameters (with its turn
    errors when it fitted any), one per trial (trials of one path share one)."""
    cache: dict[EncoderPath, PathPrediction] = {}
    out = []
    for path in trials.paths:
        if path not in cache:
            cache[path] = predict_calibrated(path, calibration)
        out.append(cache[path])
    return out


def predict_calibrated(path: EncoderPath, calibration: EstimateResult) -> PathPrediction:
    """One path's prediction at the calibration's parameters (with its turn
    errors when it fitted any: the Jacobian then spans every fitted parameter)."""
    names = [p.name for p in calibration.parameters]
    if len(names) > len(PARAMETER_NAMES):
        return predict_fitted(path, names, [p.value for p in calibration.parameters])
    return predict_path(path, calibration.params)


def parameter_covariance(calibration: EstimateResult) -> FloatArray | None:
    """The estimate's covariance (SI; 4 x 4, or one row more per turn error of
    a general-path fit), or None when it is not finite (a parameter the
    calibration did not determine)."""
    cov = np.array(calibration.covariance, dtype=np.float64)
    names = [p.name for p in calibration.parameters]
    q = len(names)
    if cov.shape != (q, q):
        return None
    if q > len(PARAMETER_NAMES):
        # a general-path fit: a variance rate on its floor has no finite
        # variance; it barely moves the predicted mean, so it is left out of
        # the propagation (the mean parameters' must be finite)
        rates = [j for j, name in enumerate(names) if name in ("K_theta", "K_rho", "K_spin")]
        bad = [j for j in rates if not np.all(np.isfinite(cov[j])) or not np.isfinite(cov[j, j])]
        cov[bad, :] = 0.0
        cov[:, bad] = 0.0
    if not np.all(np.isfinite(cov)):
        return None
    return cov


def check_trials(
    trials: ValidationTrials, calibration: EstimateResult, alpha: float = DEFAULT_ALPHA
) -> ValidationResult:
    """The NEES tests of ``trials`` against the calibrated model, the estimate's
    covariance included when it is finite.

    Raises:
        ParameterError: alpha out of range, or a singular predicted covariance.
    """
    return validation_test(
        trials.poses,
        predictions_of(trials, calibration),
        trials.covs,
        parameter_covariance(calibration),
        alpha=alpha,
        parameter_dofs=parameter_dofs(calibration),
    )


def parameter_dofs(calibration: EstimateResult) -> tuple[float, ...]:
    """Per parameter, the degrees of freedom of its variance: the interval's
    (Satterthwaite for E_R, E_T and the turn errors), else a variance rate's
    own 2 (K / SE)^2; inf where neither is known."""
    out = []
    for p in calibration.parameters:
        if p.dof is not None and p.dof > 0:
            out.append(float(p.dof))
        elif p.name in VARIANCE_RATES and p.value > 0 and 0 < p.stderr < math.inf:
            out.append(2.0 * (p.value / p.stderr) ** 2)
        else:
            out.append(math.inf)
    return tuple(out)


VARIANCE_RATES = ("K_theta", "K_rho", "K_spin")
"""Parameters that scale the predicted spread rather than move its mean: the
NEES tests, not the bias tests, are theirs."""


def detectable_by_name(
    tested: ValidationResult, calibration: EstimateResult
) -> dict[str, Detectable]:
    """The smallest error of each mean parameter (E_R, E_T, turn-scale errors)
    the validation's bias tests catch with probability
    :data:`~odohil.science.validation.DETECTION_POWER`, by name (SI), in the
    calibration's order; a parameter the trials' mean does not follow is left out."""
    names = [p.name for p in calibration.parameters]
    if len(names) <= len(PARAMETER_NAMES):
        names = list(PARAMETER_NAMES)
    return {
        names[d.index]: d
        for d in tested.detectable
        if d.index < len(names) and names[d.index] not in VARIANCE_RATES and math.isfinite(d.shift)
    }


def sensitivity_text(tested: ValidationResult, calibration: EstimateResult) -> str:
    """For people: ``what a pass rules out: with probability 90 % the bias
    tests catch E_R off by 0.62 deg/m or more, E_T by 1.2 %, ...``."""
    found = detectable_by_name(tested, calibration)
    if not found:
        return "what a pass rules out: no mean parameter moves these trials' mean"
    power = next(iter(found.values())).power
    parts = [f"{name} off by {paper_text(name, d.shift)}" for name, d in found.items()]
    return (
        f"what a pass rules out: with probability {100 * power:.0f} % the bias tests catch "
        + ", ".join(parts)
        + " or more (smaller errors can pass)"
    )


@dataclass(frozen=True)
class ValidationPlot:
    """One path's validation trials against its predicted ellipse (SI).

    Attributes:
        label: the path.
        ellipse: the predicted 95 % end-point ellipse and the measured end points.
        numbers: the trial numbers of the points.
    """

    label: str
    ellipse: EllipseData
    numbers: tuple[int, ...]


def plot_data(trials: ValidationTrials, calibration: EstimateResult) -> list[ValidationPlot]:
    """Per path (in order of first appearance), what a plot of the trials
    against the predicted ellipse needs (the first trial's measurement
    covariance stands for the path's). A backward one-way trial is mirrored
    (x and Delta negated) onto its forward path, so one path gives one ellipse."""
    parameter_cov = parameter_covariance(calibration)
    groups: dict[str, list[int]] = {}
    for i, label in enumerate(trials.labels):
        groups.setdefault(label, []).append(i)
    plots = []
    for label, rows in groups.items():
        prediction = predict_calibrated(trials.paths[rows[0]], calibration)
        mirror = np.array([-1.0, 1.0, -1.0])
        first = trials.backward[rows[0]]
        points = np.array(
            [trials.poses[i] * (mirror if trials.backward[i] != first else 1.0) for i in rows]
        )
        plots.append(
            ValidationPlot(
                label=label,
                ellipse=ellipse_data(points, prediction, trials.covs[rows[0]], parameter_cov),
                numbers=tuple(trials.numbers[i] for i in rows),
            )
        )
    return plots


def validation_sessions(session: Path) -> list[Path]:
    """The validation session folders of a calibration session, sorted."""
    root = session / VALIDATION_FOLDER
    if not root.is_dir():
        return []
    return sorted(p for p in root.iterdir() if (p / "journal.jsonl").is_file())


@dataclass(frozen=True)
class ValidationReport:
    """One validation session of a calibration, tested again for the report.

    Attributes:
        folder: the validation session folder.
        path: its ``--path`` text.
        result: the NEES tests, or None when they could not be made.
        plots: per path, the trials against the predicted ellipse.
        problem: why there is no result ("" otherwise).
        sensitivity: what a pass rules out (:func:`sensitivity_text`; "" without a result).
    """

    folder: Path
    path: str
    result: ValidationResult | None
    plots: tuple[ValidationPlot, ...] = ()
    problem: str = ""
    sensitivity: str = ""


def load_validations(
    session: Path, calibration: EstimateResult, alpha: float = DEFAULT_ALPHA
) -> tuple[ValidationReport, ...]:
    """The validation sessions under ``SESSION/validation/`` tested against
    ``calibration`` (a folder that cannot be read says why, in ``problem``)."""
    reports = []
    for folder in validation_sessions(session):
        path = folder.name
        try:
            state = load_session(folder).state
            path = str(state.header.settings.get("validation_path") or path)
            trials = trials_of_session(state, source=str(folder))
            result = check_trials(trials, calibration, alpha)
            plots = tuple(plot_data(trials, calibration))
        except OdohilError as exc:
            reports.append(ValidationReport(folder, path, None, problem=str(exc)))
            continue
        sensitivity = sensitivity_text(result, calibration)
        reports.append(ValidationReport(folder, path, result, plots, sensitivity=sensitivity))
    return tuple(reports)
