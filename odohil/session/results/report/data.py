"""What the report shows, as typed values recomputed from a session's journal.

:func:`load_report` replays a session folder's journal and recomputes (SI
throughout): the final estimate (the default robust method, as ``odohil
estimate`` makes it: odohil/session/results/outcome.py), the estimate after
each trial (convergence), every
design's trials with what happened to each (used, flagged, excluded,
ambiguous, down-weighted), its observables phi1..phi5 and the model's mean and
covariance of its pose change at the estimate.
"""

from __future__ import annotations

from collections.abc import Collection, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from odohil import units
from odohil.science.estimators import EstimateResult, IncrementalEstimator
from odohil.science.grouping import by_design
from odohil.science.moments import pose_moments
from odohil.science.observables import Observables, observables
from odohil.science.paths import Design, FloatArray
from odohil.session.journal.file import read_journal
from odohil.session.journal.state import CompletedTrial, SessionState, replay
from odohil.session.results.outcome import EstimateOutcome, estimate_state
from odohil.session.results.validation import ValidationReport, load_validations

DOWN_WEIGHT_BELOW = 0.5
"""A trial whose robust-fit probability of being clean is below this is
reported as an outlier the fit down-weights."""


@dataclass(frozen=True)
class TrialPoint:
    """One completed trial as the report shows it.

    Attributes:
        trial: its trial number in the plan (how users name it).
        design: its design's label (e.g. ``k=20 l=0.5 m turn``).
        pose: solved pose change (x m, y m, Delta rad), Delta in the 2 pi
            branch nearest the model's mean when there is an estimate.
        flagged: the pose from the marks is in doubt (the solver was not sure
            of its choice, or the operator kept a value the slip check doubted).
        note: why it is flagged (empty otherwise).
        excluded: left out on request (``--exclude``).
        ambiguous: left out because two candidate poses stayed plausible.
        clean_probability: the robust fit's probability that it is no
            outlier (None when the trial is not in the fit or the method
            gives none).
        mahalanobis2: its squared Mahalanobis distance from the model at the
            estimate (None when not in the fit).
    """

    trial: int
    design: str
    pose: tuple[float, float, float]
    flagged: bool = False
    note: str = ""
    excluded: bool = False
    ambiguous: bool = False
    clean_probability: float | None = None
    mahalanobis2: float | None = None

    @property
    def used(self) -> bool:
        """Whether the estimate uses the trial."""
        return not (self.excluded or self.ambiguous)

    @property
    def down_weighted(self) -> bool:
        """Whether the robust fit treats the trial as a likely outlier."""
        return self.clean_probability is not None and self.clean_probability < DOWN_WEIGHT_BELOW

    @property
    def marked(self) -> bool:
        """Whether the report must point the trial out."""
        return self.flagged or not self.used or self.down_weighted


@dataclass(frozen=True, eq=False)
class DesignReport:
    """One design of the session.

    Attributes:
        design: the design.
        trials: its completed trials, by trial number.
        measurement_cov: mean measurement covariance of its used trials, (3, 3).
        phi: phi1..phi5 of its used trials (None with fewer than 2).
        model_mean: the model's mean pose change at the estimate, (3,), or None.
        model_cov: the model's covariance at the estimate, (3, 3), or None.
    """

    design: Design
    trials: tuple[TrialPoint, ...]
    measurement_cov: FloatArray
    phi: Observables | None
    model_mean: FloatArray | None
    model_cov: FloatArray | None

    @property
    def signed_distance_m(self) -> float:
        """Signed encoder distance of one trial (2kl for the turn variant), m."""
        return self.design.path().signed_distance_m

    @property
    def n_used(self) -> int:
        """How many of its trials the estimate uses."""
        return sum(t.used for t in self.trials)


@dataclass(frozen=True)
class ConvergencePoint:
    """The estimate after ``n_trials`` trials (SI values and standard errors)."""

    n_trials: int
    values: tuple[float, float, float, float]
    stderr: tuple[float, float, float, float]


@dataclass(frozen=True, eq=False)
class SessionReport:
    """Everything the report shows (SI).

    Attributes:
        folder: the session folder.
        state: the replayed session.
        result: the final estimate, or None when the trials give none.
        problem: why there is no estimate (empty otherwise).
        designs: per design, in plan order of first appearance.
        convergence: the incremental estimate after each trial that gave one.
        validations: the validation sessions under ``SESSION/validation/``,
            tested against the estimate (odohil/session/results/validation.py).
        outcome: the recipe's outcome the estimate comes from
            (odohil/session/results/outcome.py).
    """

    folder: Path
    state: SessionState
    result: EstimateResult | None
    problem: str
    designs: tuple[DesignReport, ...]
    convergence: tuple[ConvergencePoint, ...]
    validations: tuple[ValidationReport, ...] = ()
    outcome: EstimateOutcome | None = None

    @property
    def trials(self) -> tuple[TrialPoint, ...]:
        """Every completed trial, by trial number."""
        return tuple(sorted((t for d in self.designs for t in d.trials), key=lambda t: t.trial))

    @property
    def marked_trials(self) -> tuple[TrialPoint, ...]:
        """The trials the report points out (flagged, left out, down-weighted)."""
        return tuple(t for t in self.trials if t.marked)


def load_report(folder: str | Path, exclude: Collection[int] = frozenset()) -> SessionReport:
    """Replay the session in ``folder`` and recompute the estimates (the
    default robust method), leaving out the trial numbers in ``exclude``.

    Raises:
        JournalError: no readable, consistent journal there.
        MeasurementError: an excluded number that is no completed trial's.
    """
    path = Path(folder)
    state = replay(read_journal(path).records)
    outcome = estimate_state(state, exclude, source=str(path))
    kept = [o for o in outcome.observations if o.trial not in set(outcome.excluded)]
    result, problem = outcome.result, outcome.problem
    convergence: list[ConvergencePoint] = []
    incremental = IncrementalEstimator()
    for n, obs in enumerate(kept, start=1):
        fit = incremental.add(obs)
        if fit is None:
            continue
        diag = np.diag(np.asarray(fit.covariance, dtype=np.float64))
        se = np.sqrt(np.where(np.isfinite(diag), np.clip(diag, 0.0, None), np.inf))
        convergence.append(ConvergencePoint(n, fit.params.as_tuple(), (se[0], se[1], se[2], se[3])))
    fit_order = [o.trial for o in kept]
    designs = _designs(state.completed, set(exclude), fit_order, result)
    validations = load_validations(path, result) if result is not None else ()
    return SessionReport(
        path, state, result, problem, designs, tuple(convergence), validations, outcome
    )


def _designs(
    completed: Sequence[CompletedTrial],
    excluded: set[int],
    fit_order: Sequence[int | None],
    result: EstimateResult | None,
) -> tuple[DesignReport, ...]:
    d2: dict[int, float] = {}
    clean: dict[int, float] = {}
    if result is not None:
        distances = result.model_check.mahalanobis2
        if len(distances) == len(fit_order):  # in the fit's input order
            d2 = {t: v for t, v in zip(fit_order, distances, strict=True) if t is not None}
        clean = {t.trial: t.clean_probability for t in result.trials}
    out = []
    for design, members in by_design(sorted(completed, key=lambda t: t.trial)).items():
        model_mean = model_cov = None
        if result is not None:
            moments = pose_moments(design.path(), result.params)
            model_mean, model_cov = moments.mean, moments.cov
        points = tuple(
            TrialPoint(
                trial=t.trial,
                design=design.label(),
                pose=_near_mean(t.pose_change, model_mean),
                flagged=not t.clear_cut or bool(t.flag_reason),
                note="; ".join(part for part in (t.note, t.flag_reason) if part),
                excluded=t.trial in excluded,
                ambiguous=t.ambiguous,
                clean_probability=clean.get(t.trial),
                mahalanobis2=d2.get(t.trial),
            )
            for t in members
        )
        used = [t for t, p in zip(members, points, strict=True) if p.used]
        covs = [np.array(t.cov, dtype=np.float64) for t in (used or members)]
        poses = np.array([p.pose for p in points if p.used], dtype=np.float64).reshape(-1, 3)
        phi = observables(poses) if len(poses) >= 2 else None
        out.append(DesignReport(design, points, np.mean(covs, axis=0), phi, model_mean, model_cov))
    return tuple(out)


def _near_mean(
    pose: tuple[float, float, float], mean: FloatArray | None
) -> tuple[float, float, float]:
    """Headings are known modulo 2 pi: put the trial's in the branch nearest the model mean."""
    x, y, heading = pose
    if mean is None:
        return (x, y, heading)
    centre = float(mean[2])
    return (x, y, units.angle_near(heading, centre))
