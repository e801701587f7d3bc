"""The one recipe from a session or a trial file to an estimate and its verdict.

Every command that estimates (run, resume, the wizard, estimate, report,
export, validate, demo) calls :func:`estimate_state`, :func:`estimate_path`
or :func:`estimate_source` and renders the :class:`EstimateOutcome` it
returns, so one session gets one verdict whichever command reads it: the same
trials (every solved trial but the ambiguous ones and those left out on
request), the same method, and the robot's ``[robot] turns_exact`` from its
description (journaled in a session, ``--robot`` for a file or a recording).

One loader, :func:`load_source`, tells the sources apart (:func:`source_kind`):
a session folder, a forth-and-back trial file (pose rows or raw marks), a
general-path trial file (what ``odohil import`` writes) or a recording
(any log ``odohil import`` reads: odohil log CSVs, TUM pairs, ROS 2 bags, the
optiodom data set's runs). The first two give forth-and-back observations and
the design estimator; the last two give
:class:`~odohil.science.path_trials.PathTrial` values and the general-path
estimator (:func:`~odohil.science.estimators.paths.estimate_paths`, with the
turn errors e_turn and K_spin unless the robot's turns are exact). A
:class:`Selection` keeps only the general-path trials of one family or
direction (for example the straight runs of a recording that holds straight
runs and spins).

Besides the verdict (can the estimate be trusted within its uncertainty?) an
outcome says whether the estimate is precise enough to be exported
(:attr:`EstimateOutcome.export_refusals`): a correction whose 95 % interval is
wider than the correction itself, or a design with fewer trials than the
planner's minimum, is no honest configuration for a fusion stack.
"""

from __future__ import annotations

from collections.abc import Collection, Iterable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Literal

import numpy as np

from odohil import units
from odohil.errors import MeasurementError, ParameterError, TrialFileError
from odohil.science.estimators import EstimateResult, Observation, estimate
from odohil.science.estimators.estimate import Method
from odohil.science.estimators.paths import PATH_METHODS, estimate_paths
from odohil.science.estimators.verdict import Verdict, few_trial_designs
from odohil.science.path_trials import PathTrial
from odohil.science.planner import DEFAULT_MIN_TRIALS_PER_DESIGN
from odohil.science.robot_description import RobotDescription
from odohil.session.bounded_io import check_regular_file
from odohil.session.journal.file import TornRecord
from odohil.session.journal.state import (
    SessionState,
    description_of_header,
    load_session,
    session_path_trials,
    session_trials,
)
from odohil.session.progress import stage
from odohil.session.trials.logs import Cut, ImportOptions, WindowCount, guess_format, read_cut
from odohil.session.trials.logs.csv_log import TIME_COLUMN
from odohil.session.trials.path_trial_file import is_path_trial_file, read_path_trials, summary_rows
from odohil.session.trials.trial_file import Trial, TrialSet, read_trials

__all__ = [
    "EstimateOutcome",
    "Selection",
    "check_exclude",
    "estimate_source",
    "estimate_state",
    "parse_exclude",
    "source_kind",
]

Status = Literal["trusted", "doubtful", "failed", "no estimate"]
SourceKind = Literal["session", "trials", "path-trials", "recording"]
"""A session folder, a forth-and-back trial file, a general-path trial file,
a recording (module docstring)."""


@dataclass(frozen=True, eq=False)
class EstimateOutcome:
    """What the trials of a session or a trial file give.

    Attributes:
        source: the session folder or trial file, as named.
        trials: the trials read (flagged ones marked, ambiguous ones apart).
        observations: the trials as the estimator sees them, numbered (a
            session's trial numbers, a file's 1-based row positions).
        ambiguous: trial numbers left out because two poses stay plausible.
        excluded: trial numbers left out on request (``--exclude``).
        result: the estimate, or None when the trials give none.
        problem: why there is no estimate ("" when there is one).
        export_refusals: why the estimate must not be exported without
            ``--force`` although trusted (too few trials a design, a correction
            not told from none); empty when it may be.
        torn: the session journal's torn last record, not used (None when
            there is none or the source is a file).
        path_trials: the general-path trials estimated from (a general-path
            trial file or a recording, after the selection); empty for a
            session or a forth-and-back trial file.
        path_flagged: (trial number, why) of the trials of a session with
            general paths whose pose from the marks is in doubt (the others'
            come from ``trials``).
        windows: how a recording cut by ``--window-m`` went (windows used,
            left out for a gap in the ground truth, partial ones dropped);
            None otherwise.
    """

    source: str
    trials: TrialSet
    observations: tuple[Observation, ...]
    ambiguous: tuple[int, ...]
    excluded: tuple[int, ...]
    result: EstimateResult | None
    problem: str = ""
    export_refusals: tuple[str, ...] = ()
    torn: TornRecord | None = None
    path_trials: tuple[PathTrial, ...] = ()
    path_flagged: tuple[tuple[int, str], ...] = ()
    windows: WindowCount | None = None

    @property
    def verdict(self) -> Verdict | None:
        """The estimate's verdict (None without an estimate)."""
        return None if self.result is None else self.result.verdict

    @property
    def status(self) -> Status:
        """``trusted``, ``doubtful``, ``failed`` or ``no estimate``."""
        return "no estimate" if self.result is None else self.result.verdict.status

    @property
    def trusted(self) -> bool:
        """Whether there is an estimate and it is trusted."""
        return self.result is not None and self.result.verdict.trusted

    @property
    def exportable(self) -> bool:
        """Whether the estimate may be exported without ``--force``."""
        return self.trusted and not self.export_refusals

    def to_json_dict(self) -> dict[str, Any]:
        """The estimate's JSON object (SI) with the flagged and ambiguous trials
        and the export refusals; without an estimate, its verdict is
        ``no estimate`` with the reason."""
        if self.result is None:
            data: dict[str, Any] = {
                "verdict": {"status": self.status, "reasons": [self.problem]},
                "n_trials": len(self.observations) or len(self.path_trials),
                "excluded": list(self.excluded),
            }
        else:
            data = self.result.to_json_dict()
        data["flagged_trials"] = [trial for trial, _ in self.flagged]
        data["ambiguous_trials"] = list(self.ambiguous)
        data["export_refusals"] = list(self.export_refusals)
        if self.path_trials:
            data["general_paths"] = [
                {"family": family, "direction": direction, "trials": n, "distance_m": dist}
                for family, direction, n, dist in summary_rows(self.path_trials)
            ]
        if self.windows is not None:
            data["windows"] = self.windows.to_json_dict()
        return data

    @property
    def flagged(self) -> tuple[tuple[int, str], ...]:
        """(trial number, why) of the trials whose pose from the marks is in doubt."""
        return self.path_flagged + tuple(
            (o.trial or 0, t.note)
            for o, t in zip(self.observations, self.trials.trials, strict=True)
            if t.flagged
        )


def estimate_trials(
    trials: TrialSet,
    turns_exact: bool,
    exclude: Collection[int] = (),
    method: Method = "robust",
    source: str = "",
    torn: TornRecord | None = None,
) -> EstimateOutcome:
    """The recipe: the estimate of ``trials`` and its verdict.

    Trials are numbered by their own number (sessions) or their 1-based
    position among the file's rows, ambiguous rows included.

    Raises:
        MeasurementError: an excluded number that is no trial's (naming
            ``--exclude`` and the trial numbers there are).
    """
    rows = sorted((*trials.trials, *trials.ambiguous), key=lambda t: t.line)
    position = {t.line: i for i, t in enumerate(rows)}
    observations = tuple(_observation(t, position[t.line]) for t in trials.trials)
    ambiguous = tuple(
        t.number if t.number is not None else position[t.line] + 1 for t in trials.ambiguous
    )
    check_exclude(exclude, [o.trial for o in observations if o.trial is not None])
    left_out = tuple(sorted(exclude))
    name = source or trials.source
    if not observations:
        problem = "no trials to estimate from" + (
            f" ({units.plural(len(ambiguous), 'ambiguous trial')} left out)" if ambiguous else ""
        )
        return EstimateOutcome(name, trials, (), ambiguous, left_out, None, problem, torn=torn)
    try:
        result = estimate(
            observations,
            method,
            exclude=left_out,
            ambiguous=ambiguous,
            turns_exact=turns_exact,
        )
    except MeasurementError as exc:
        return EstimateOutcome(
            name, trials, observations, ambiguous, left_out, None, str(exc), torn=torn
        )
    used = [o for o in observations if o.trial not in set(left_out)]
    refusals = export_refusals(result, used)
    return EstimateOutcome(
        name, trials, observations, ambiguous, left_out, result, "", refusals, torn
    )


def estimate_state(
    state: SessionState,
    exclude: Collection[int] = (),
    method: Method = "robust",
    source: str = "session",
    torn: TornRecord | None = None,
) -> EstimateOutcome:
    """The outcome of a session's completed trials (``turns_exact`` from its
    journaled robot description). A session whose plan names a general path
    is estimated by the general-path estimator (every trial, forth-and-back
    ones as their design's encoder path; ambiguous ones left out).

    Raises:
        JournalError: the session holds no robot description.
        MeasurementError: an excluded number that is no completed trial's.
    """
    turns_exact = description_of_header(state).robot.turns_exact
    if state.plan is not None and state.plan.has_paths:
        return _session_paths_outcome(state, turns_exact, exclude, method, source, torn)
    return estimate_trials(
        session_trials(state, source=source), turns_exact, exclude, method, source, torn
    )


def _session_paths_outcome(
    state: SessionState,
    turns_exact: bool,
    exclude: Collection[int],
    method: str,
    source: str,
    torn: TornRecord | None,
) -> EstimateOutcome:
    """:func:`estimate_path_trials` of a session with general paths, its
    ambiguous trials and torn record named."""
    trials = session_path_trials(state, source=source)
    ambiguous = tuple(t.trial for t in state.completed if t.ambiguous)
    if not trials:
        problem = "no trials to estimate from" + (
            f" ({units.plural(len(ambiguous), 'ambiguous trial')} left out)" if ambiguous else ""
        )
        empty = TrialSet((), "pose", source)
        return EstimateOutcome(
            source, empty, (), ambiguous, tuple(sorted(exclude)), None, problem, torn=torn
        )
    if method == "paper":
        raise ParameterError(
            "--method paper: a session with general paths is fitted by " + " or ".join(PATH_METHODS)
        )
    outcome = estimate_path_trials(trials, turns_exact, exclude, method, source)
    flagged = tuple(
        (t.trial, "; ".join(part for part in (t.note, t.flag_reason) if part))
        for t in state.completed
        if not t.ambiguous and (not t.clear_cut or t.flag_reason)
    )  # as session_trials flags a forth-and-back trial
    return replace(outcome, ambiguous=ambiguous, torn=torn, path_flagged=flagged)


def estimate_path(
    path: Path,
    description: RobotDescription | None = None,
    exclude: Collection[int] = (),
    method: Method = "robust",
) -> EstimateOutcome:
    """The outcome of a session folder (its journal; a torn last record is not
    used and is named in :attr:`EstimateOutcome.torn`) or a trial file (raw
    marks need ``description``; without one the robot is taken to turn
    without error, as the paper's).

    Raises:
        JournalError: not a session folder, or a corrupt journal.
        TrialFileError: the file cannot be used (every bad row listed).
        MeasurementError: an excluded number that is no trial's.
    """
    if path.is_dir():
        loaded = load_session(path)
        return estimate_state(loaded.state, exclude, method, str(path), loaded.torn)
    turns_exact = description.robot.turns_exact if description is not None else True
    return estimate_trials(read_trials(path, description), turns_exact, exclude, method, str(path))


def export_refusals(
    result: EstimateResult,
    used: Sequence[Observation],
    min_trials_per_design: int = DEFAULT_MIN_TRIALS_PER_DESIGN,
) -> tuple[str, ...]:
    """Why ``result`` is not precise enough to export, one sentence each:
    a design with fewer than ``min_trials_per_design`` trials (the planner's
    minimum for honest intervals), or a correction (distance scale 1 + E_T,
    heading drift E_R) whose 95 % interval is wider than the correction."""
    reasons = []
    few = few_trial_designs(used, min_trials_per_design)
    if few:
        reasons.append(
            f"fewer than {units.plural(min_trials_per_design, 'trial')} a design, the "
            f"planner's minimum for honest intervals: {', '.join(few)}"
        )
    reasons.extend(_correction_refusals(result))
    return tuple(reasons)


def _correction_refusals(result: EstimateResult) -> list[str]:
    """A correction (distance scale 1 + E_T, heading drift E_R) whose 95 %
    interval is wider than the correction, one sentence each."""
    reasons = []
    for name, what in (("E_T", "distance scale 1 + E_T"), ("E_R", "heading drift E_R")):
        p = result.parameter(name)
        low, high = p.ci95
        if not (np.isfinite(low) and np.isfinite(high)) or high - low > abs(p.value):
            unit = units.parameter_unit(name, "paper")
            low_p, high_p, value_p = (
                units.parameter_in(name, v, "paper") for v in (low, high, p.value)
            )
            reasons.append(
                f"the {what} correction is not told from none: {name}'s 95 % interval "
                f"{units.with_unit(f'[{low_p:.4g}, {high_p:.4g}]', unit)} is wider than its value "
                f"{units.with_unit(f'{value_p:.4g}', unit)}"
            )
    return reasons


def _observation(trial: Trial, position: int) -> Observation:
    cov = trial.pose_cov if trial.pose_cov is not None else np.zeros((3, 3))
    number = trial.number if trial.number is not None else position + 1
    return Observation(trial.design, trial.pose_change, cov, line=trial.line, trial=number)


def parse_exclude(text: str | None) -> frozenset[int]:
    """The trial numbers of ``--exclude`` (empty for None or "").

    Raises:
        MeasurementError: not a comma-separated list of positive integers
            (the message names ``--exclude``).
    """
    if text is None or not text.strip():
        return frozenset()
    numbers: set[int] = set()
    for part in text.split(","):
        item = part.strip()
        if not item.isdigit() or int(item) < 1:
            raise MeasurementError(
                f"--exclude: {item!r} is not a trial number; give positive integers "
                "separated by commas, e.g. --exclude 3,17"
            )
        numbers.add(int(item))
    return frozenset(numbers)


def check_exclude(numbers: Iterable[int], available: Iterable[int]) -> None:
    """Every excluded number must be a trial's.

    Raises:
        MeasurementError: naming ``--exclude`` and the trial numbers accepted.
    """
    have = sorted(set(available))
    missing = sorted(set(numbers) - set(have))
    if missing:
        span = f"{have[0]}..{have[-1]}" if have else "none yet"
        raise MeasurementError(
            f"--exclude: no trial numbered {', '.join(str(t) for t in missing)} "
            f"(the trials are numbered {span})"
        )


@dataclass(frozen=True)
class Selection:
    """Which general-path trials of a source to use (None: all).

    Attributes:
        family: keep the trials of this path family only (``straight``,
            ``spin``, ``arc``, ``square``, ...: what ``odohil import`` lists).
        direction: keep the trials of this direction only (``forward``,
            ``backward``, ``cw``, ``ccw``, ``mixed``).
    """

    family: str | None = None
    direction: str | None = None

    @property
    def chosen(self) -> bool:
        """Whether anything is selected."""
        return self.family is not None or self.direction is not None

    def apply(self, trials: Sequence[PathTrial], source: str) -> list[PathTrial]:
        """The trials selected.

        Raises:
            ParameterError: none is left (naming ``--family``/``--direction``
                and the groups the source holds).
        """
        kept = [
            t
            for t in trials
            if (self.family is None or t.family == self.family)
            and (self.direction is None or t.direction == self.direction)
        ]
        if not kept:
            held = ", ".join(f"{f} {d} ({n})" for f, d, n, _ in summary_rows(trials))
            asked = " ".join(
                f"{option} {value}"
                for option, value in (("--family", self.family), ("--direction", self.direction))
                if value is not None
            )
            raise ParameterError(
                f"{asked}: no trial of {source} is selected; it holds (family direction, "
                f"trials): {held}"
            )
        return kept


def _is_log_csv(path: Path) -> bool:
    """Whether a CSV file's first line names the log column ``t_s`` (a
    recording; a forth-and-back trial file has no time column)."""
    try:
        with open(path, encoding="utf-8", errors="replace") as stream:
            for line in stream:
                if line.strip() and not line.lstrip().startswith("#"):
                    return TIME_COLUMN in [f.strip() for f in line.split(",")]
    except OSError:
        return False
    return False


def source_kind(paths: Sequence[Path], recording: ImportOptions | None = None) -> SourceKind:
    """What the paths are (module docstring): a session folder (it holds a
    journal), a general-path trial file (its header line), a forth-and-back
    trial file (a CSV without a ``t_s`` column), else a recording; a log
    ``--format`` given makes them a recording.

    Raises:
        TrialFileError: a path that is neither a folder nor a regular file
            (a FIFO, a device), before anything reads it.
    """
    for path in paths:
        if path.exists() and not path.is_dir():
            check_regular_file(path, "trial file", TrialFileError)  # never a FIFO or a device
    if len(paths) == 1 and (recording is None or recording.format is None):
        path = paths[0]
        if path.is_dir() and (path / "journal.jsonl").exists():
            return "session"
        if is_path_trial_file(path):
            return "path-trials"
        if path.is_file() and guess_format([path]) == "csv" and not _is_log_csv(path):
            return "trials"
    return "recording"


def load_path_trials(
    paths: Sequence[Path],
    description: RobotDescription | None,
    recording: ImportOptions | None = None,
    selection: Selection | None = None,
) -> list[PathTrial]:
    """The general-path trials of a general-path trial file or a recording,
    selected (:func:`load_path_cut`'s trials)."""
    return list(load_path_cut(paths, description, recording, selection).trials)


def load_path_cut(
    paths: Sequence[Path],
    description: RobotDescription | None,
    recording: ImportOptions | None = None,
    selection: Selection | None = None,
) -> Cut:
    """The general-path trials of a general-path trial file or a recording,
    selected, and how a recording's windows went (``--window-m``).

    Raises:
        ParameterError: a recording without a robot description (``--robot``),
            a selection that keeps nothing, ``--window-m`` on a trial file.
        TrialFileError, RecordingError: the files cannot be used.
    """
    kind = source_kind(paths, recording)
    name = ", ".join(map(str, paths))
    recording = recording or ImportOptions()
    if kind == "path-trials":
        if recording.window_m is not None:
            raise ParameterError(
                f"--window-m cuts a recording; {name} is a general-path trial file, "
                "already cut into trials"
            )
        cut = Cut(tuple(read_path_trials(paths[0])))
    elif kind == "recording":
        if description is None:
            raise ParameterError(
                f"--robot is needed to read the recording {name}: its [robot] geometry and "
                "turns_exact come from the robot description"
            )
        cut = read_cut(paths, description, recording)
    else:
        raise ParameterError(f"{name} is a {kind}, not a recording or a general-path trial file")
    return replace(cut, trials=tuple((selection or Selection()).apply(cut.trials, name)))


def estimate_path_trials(
    trials: Sequence[PathTrial],
    turns_exact: bool,
    exclude: Collection[int] = (),
    method: str = "robust",
    source: str = "",
) -> EstimateOutcome:
    """The recipe for general paths: :func:`estimate_paths` of ``trials``
    (turn errors fitted unless ``turns_exact``) and its verdict.

    Raises:
        ParameterError: a method the general-path estimator does not have.
        MeasurementError: an excluded number that is no trial's.
    """
    if method not in PATH_METHODS:
        raise ParameterError(
            f"--method {method}: general-path trials are fitted by {' or '.join(PATH_METHODS)}"
        )
    check_exclude(exclude, [t.trial for t in trials if t.trial is not None])
    left_out = tuple(sorted(exclude))
    empty = TrialSet((), "pose", source)
    kept = tuple(trials)
    try:
        result = estimate_paths(kept, turns_exact=turns_exact, method=method, exclude=left_out)
    except MeasurementError as exc:
        return EstimateOutcome(source, empty, (), (), left_out, None, str(exc), path_trials=kept)
    used = [t for t in kept if t.trial not in set(left_out)]
    refusals = path_export_refusals(result, used)
    return EstimateOutcome(source, empty, (), (), left_out, result, "", refusals, None, kept)


def estimate_source(
    paths: Sequence[Path],
    description: RobotDescription | None = None,
    exclude: Collection[int] = (),
    method: str = "robust",
    recording: ImportOptions | None = None,
    selection: Selection | None = None,
) -> EstimateOutcome:
    """The one loader and recipe (module docstring): the outcome of a session
    folder, a forth-and-back trial file, a general-path trial file or a
    recording. ``description`` (``--robot``) gives ``turns_exact`` for files
    and recordings (a file without one: turns exact) and is required for a
    recording.

    Raises:
        ParameterError: several paths that are no recording, a selection on a
            forth-and-back source, a recording without ``description``, a
            method the general-path estimator does not have.
        JournalError, TrialFileError, RecordingError: the source cannot be used.
        MeasurementError: an excluded number that is no trial's.
    """
    files = [Path(p) for p in paths]
    if not files:
        raise ParameterError("no session, trial file or recording given")
    for file in files:
        if not file.exists():
            raise ParameterError(
                f"{file}: no such session folder (journal.jsonl), trial file or recording"
            )
    kind = source_kind(files, recording)
    selection = selection or Selection()
    if kind in ("session", "trials"):
        if selection.chosen:
            raise ParameterError(
                f"--family/--direction select general-path trials (recordings, files of "
                f"`odohil import`); {files[0]} is a "
                + ("session" if kind == "session" else "trial file")
            )
        if recording is not None and recording.window_m is not None:
            raise ParameterError(
                f"--window-m cuts a recording; {files[0]} is a "
                + ("session" if kind == "session" else "trial file")
            )
        if method not in ("robust", "joint", "paper"):
            raise ParameterError(f"--method {method}: one of robust, joint, paper")
        return estimate_path(files[0], description, exclude, method)  # type: ignore[arg-type]
    cut = load_path_cut(files, description, recording, selection)
    turns_exact = description.robot.turns_exact if description is not None else True
    with stage(recording.progress if recording is not None else None, FITTING):
        outcome = estimate_path_trials(
            cut.trials, turns_exact, exclude, method, ", ".join(str(p) for p in files)
        )
    return replace(outcome, windows=cut.windows)


FITTING = "fitting"
"""The progress stage of the fit of :func:`estimate_source` (one count: the fit)."""


def path_export_refusals(
    result: EstimateResult,
    used: Sequence[PathTrial],
    min_trials_per_group: int = DEFAULT_MIN_TRIALS_PER_DESIGN,
) -> tuple[str, ...]:
    """:func:`export_refusals` for general paths: a path family and direction
    with fewer than ``min_trials_per_group`` trials, or a correction not told
    from none."""
    reasons = []
    few = [
        f"{family} {direction} ({n})"
        for family, direction, n, _ in summary_rows(used)
        if n < min_trials_per_group
    ]
    if few:
        reasons.append(
            f"fewer than {units.plural(min_trials_per_group, 'trial')} a path family and "
            "direction, the "
            f"planner's minimum for honest intervals: {', '.join(few)}"
        )
    reasons.extend(_correction_refusals(result))
    return tuple(reasons)
