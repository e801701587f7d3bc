"""The one recipe from a session or a trial file to an estimate and its verdict.

Every command that estimates (run, resume, the wizard, estimate, report,
export, validate, demo) calls :func:`estimate_state` or :func:`estimate_path`
and renders the :class:`EstimateOutcome` it returns, so one session gets one
verdict whichever command reads it: the same trials (every solved trial but
the ambiguous ones and those left out on request), the same method, and the
robot's ``[robot] turns_exact`` from its description (journaled in a session,
``--robot`` for a trial file).

Besides the verdict (can the estimate be trusted within its uncertainty?) an
outcome says whether the estimate is precise enough to be exported
(:attr:`EstimateOutcome.export_refusals`): a correction whose 95 % interval is
wider than the correction itself, or a design with fewer trials than the
planner's minimum, is no honest configuration for a fusion stack.
"""

from __future__ import annotations

from collections.abc import Collection, Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import numpy as np

from odohil import units
from odohil.errors import MeasurementError
from odohil.science.estimators import EstimateResult, Observation, estimate
from odohil.science.estimators.estimate import Method
from odohil.science.estimators.verdict import Verdict
from odohil.science.grouping import by_design
from odohil.science.planner import DEFAULT_MIN_TRIALS_PER_DESIGN
from odohil.science.robot_description import RobotDescription
from odohil.session.journal import TornRecord
from odohil.session.state import (
    SessionState,
    description_of_header,
    load_session,
    session_trials,
)
from odohil.session.trial_files import Trial, TrialSet, read_trials

Status = Literal["trusted", "doubtful", "failed", "no estimate"]


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
                "n_trials": len(self.observations),
                "excluded": list(self.excluded),
            }
        else:
            data = self.result.to_json_dict()
        data["flagged_trials"] = [trial for trial, _ in self.flagged]
        data["ambiguous_trials"] = list(self.ambiguous)
        data["export_refusals"] = list(self.export_refusals)
        return data

    @property
    def flagged(self) -> tuple[tuple[int, str], ...]:
        """(trial number, why) of the trials whose pose from the marks is in doubt."""
        return tuple(
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
    journaled robot description).

    Raises:
        JournalError: the session holds no robot description.
        MeasurementError: an excluded number that is no completed trial's.
    """
    turns_exact = description_of_header(state).robot.turns_exact
    return estimate_trials(
        session_trials(state, source=source), turns_exact, exclude, method, source, torn
    )


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
    few = [
        f"{design.label()} ({len(members)})"
        for design, members in by_design(used, lambda o: o.design.forward).items()
        if len(members) < min_trials_per_design
    ]
    if few:
        reasons.append(
            f"fewer than {min_trials_per_design} trials a design, the planner's minimum "
            f"for honest intervals: {', '.join(few)}"
        )
    for name, what in (("E_T", "distance scale 1 + E_T"), ("E_R", "heading drift E_R")):
        p = result.parameter(name)
        low, high = p.ci95
        if not (np.isfinite(low) and np.isfinite(high)) or high - low > abs(p.value):
            reasons.append(
                f"the {what} correction is not told from none: {name}'s 95 % interval "
                f"[{low:.4g}, {high:.4g}] is wider than its value {p.value:.4g}"
            )
    return tuple(reasons)


def _observation(trial: Trial, position: int) -> Observation:
    cov = trial.pose_cov if trial.pose_cov is not None else np.zeros((3, 3))
    number = trial.number if trial.number is not None else position + 1
    return Observation(trial.design, trial.pose_change, cov, line=trial.line, trial=number)


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
