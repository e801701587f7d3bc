"""One call from trials to an :class:`EstimateResult`, by any method, with its verdict."""

from __future__ import annotations

import math
from collections.abc import Hashable, Iterable, Sequence
from dataclasses import replace
from typing import Literal

import numpy as np

from odohil import units
from odohil.errors import MeasurementError
from odohil.science import distributions
from odohil.science.estimators.checks import Criteria, design_misfit, model_check, sufficiency
from odohil.science.estimators.intervals import profile_interval, satterthwaite_dofs, t_interval
from odohil.science.estimators.joint import JointFit, joint_estimate, start_phi
from odohil.science.estimators.likelihood import GroupStats
from odohil.science.estimators.memo import ResultMemo
from odohil.science.estimators.observations import (
    DesignSummary,
    Observation,
    TrialGroup,
    forward_view,
    group_trials,
    summarise,
)
from odohil.science.estimators.paper import PaperEstimate, paper_estimate
from odohil.science.estimators.result import (
    EstimateResult,
    ParameterEstimate,
    TrialDiagnostic,
)
from odohil.science.estimators.robust import (
    EPSILON,
    INFLATION,
    OUTLIER_WEIGHT,
    robust_fit,
    weighted_groups,
)
from odohil.science.estimators.scores import sandwich_ratio, trial_scores
from odohil.science.estimators.verdict import judge
from odohil.science.parameters import PARAMETER_NAMES, ErrorParameters, si_unit
from odohil.science.paths import FloatArray

Method = Literal["robust", "joint", "paper"]
METHODS: tuple[Method, ...] = ("robust", "joint", "paper")


def paper_notes(paper: PaperEstimate) -> tuple[str, ...]:
    """Which designs gave which parameters."""
    return (
        f"E_R, K_theta, E_T from {paper.first.design.label()} "
        f"({units.plural(paper.first.n, 'trial')}); "
        f"K_rho from {paper.second.design.label()} ({units.plural(paper.second.n, 'trial')})",
    )


def joint_start(paper: PaperEstimate) -> FloatArray:
    """The paper estimate as a start for the likelihood, variance rates raised
    to at least their standard errors when they came out at or near 0."""
    se = np.sqrt(np.clip(np.diag(paper.covariance), 0.0, None))
    floor = ErrorParameters(
        0.0,
        0.0,
        float(se[2]) if math.isfinite(se[2]) else 0.0,
        float(se[3]) if math.isfinite(se[3]) else 0.0,
    )
    return start_phi(paper.params, floor)


def interval_dof(n_trials: int) -> int:
    """3 n - 4 (at least 1): the Wald intervals' t degrees of freedom."""
    return max(1, 3 * n_trials - 4)


def _estimates(
    params: ErrorParameters, cov: FloatArray, n_trials: int
) -> tuple[tuple[ParameterEstimate, ...], FloatArray]:
    """The Wald intervals (the cheap rule of the live estimate, of the paper
    method and of the Gaussian fit reported beside the robust one)."""
    diag = np.diag(cov)
    stderr = np.sqrt(np.where(np.isfinite(diag), np.clip(diag, 0.0, None), np.inf))
    base = interval_dof(n_trials)
    estimates = []
    for name, value, se in zip(PARAMETER_NAMES, params.as_tuple(), stderr, strict=True):
        dof = _dof(name, value, float(se), base)
        q = distributions.t_ppf(0.975, dof)  # the t quantile
        estimates.append(ParameterEstimate.build(name, value, float(se), q, dof))
    return tuple(estimates), stderr


def _dof(name: str, value: float, stderr: float, base: float) -> float:
    """The t degrees of freedom of a Wald interval: ``base`` (3 n - 4) for E_R
    and E_T; for a variance rate the Satterthwaite degrees of freedom of its
    own precision, 2 (K / stderr)^2 (a variance estimated from nu squares has
    relative standard error sqrt(2 / nu)), when that is the smaller."""
    if name not in ("K_theta", "K_rho") or not (value > 0 and math.isfinite(stderr)):
        return base
    if stderr <= 0:
        return base
    return min(base, max(2.0 * (value / stderr) ** 2, 1.0))


def honest_estimates(
    groups: Sequence[GroupStats], fit: JointFit, ratio: FloatArray
) -> tuple[ParameterEstimate, ...]:
    """The intervals of a maximum-likelihood fit of ``groups``, every parameter
    of its layout: profile likelihood for the variance rates, widened by their
    sandwich ratio (``ratio``, odohil/science/estimators/scores.py) when it
    exceeds 1, Satterthwaite t for the mean parameters (E_R, E_T, e_turn)
    (odohil/science/estimators/intervals.py)."""
    layout = fit.point.layout
    cov = np.array(fit.covariance, dtype=np.float64)
    diag = np.diag(cov)
    stderr = np.sqrt(np.where(np.isfinite(diag), np.clip(diag, 0.0, None), np.inf))
    values = fit.values
    means = [i for i in layout.mean_index if math.isfinite(stderr[i])]
    dofs = dict(zip(means, satterthwaite_dofs(groups, fit, means), strict=True)) if means else {}
    out = []
    for index, name in enumerate(layout.names):
        value, se = float(values[index]), float(stderr[index])
        if not math.isfinite(se):
            out.append(ParameterEstimate.build(name, value, se))
            continue
        if index in dofs:
            rule = "Student t, Satterthwaite degrees of freedom"
            interval = t_interval(value, se, dofs[index], rule)
        else:
            interval = profile_interval(groups, fit, index, widen=float(ratio[index]))
        out.append(
            ParameterEstimate(
                name,
                value,
                se,
                interval.ci95,
                si_unit(name),
                interval.ci_4sigma,
                interval.method,
                interval.dof,
            )
        )
    return tuple(out)


def build_result(
    method: str,
    observations: Sequence[Observation],
    summaries: Sequence[DesignSummary],
    params: ErrorParameters,
    covariance: FloatArray,
    notes: tuple[str, ...],
    criteria: Criteria | None = None,
    *,
    check_params: ErrorParameters | None = None,
    named_outliers: Sequence[int] = (),
    converged: bool = True,
    gaussian: tuple[ParameterEstimate, ...] = (),
    trials: tuple[TrialDiagnostic, ...] = (),
    excluded: tuple[int, ...] = (),
    ambiguous: Sequence[int] = (),
    intervals: tuple[ParameterEstimate, ...] = (),
    turns_exact: bool = True,
    check_covariance: FloatArray | None = None,
    backward: Sequence[bool] | None = None,
) -> EstimateResult:
    """Assemble the result, run the checks and give the verdict.

    ``check_params``: where the model check is evaluated (the maximum-likelihood
    fit; ``params`` when None), ``check_covariance`` its covariance (else
    ``covariance``). ``named_outliers``: input positions the robust
    fit named outliers (left out of the misfit checks too). ``intervals``: the
    parameters with their intervals (else the Wald rule of :func:`_estimates`).
    ``backward``: which trials were driven backwards (``observations`` are in
    the forward view), for the misfit checks' groups.
    """
    cov = np.array(covariance, dtype=np.float64)
    estimates, stderr = _estimates(params, cov, len(observations))
    if intervals:
        estimates = intervals
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov / np.outer(stderr, stderr)
    corr[~np.isfinite(corr)] = math.nan
    np.fill_diagonal(corr, 1.0)
    check = model_check(observations, check_params or params, named_outliers)
    kept = [i for i in range(len(observations)) if i not in set(named_outliers)]
    flags = list(backward) if backward is not None else None
    misfit = design_misfit(
        [observations[i] for i in kept],
        check_params or params,
        cov if check_covariance is None else np.asarray(check_covariance, dtype=np.float64),
        [flags[i] for i in kept] if flags is not None else None,
    )
    verdict = judge(
        observations,
        converged,
        [
            float(v) if math.isfinite(e.ci95[1]) else math.inf
            for v, e in zip(stderr, estimates, strict=True)
        ],
        PARAMETER_NAMES,
        check.fits,
        [o.label() for o in check.outliers],
        check.verdict,
        ambiguous,
        turns_exact,
        misfit,
    )
    if ambiguous:
        notes = (
            *notes,
            f"{len(ambiguous)} ambiguous trial(s) left out (the floor marks fit two poses): "
            + ", ".join(str(t) for t in ambiguous),
        )
    return EstimateResult(
        method=method,
        n_trials=len(observations),
        params=params,
        parameters=estimates,
        covariance=tuple(tuple(float(v) for v in row) for row in cov),
        correlation=tuple(tuple(float(v) for v in row) for row in corr),
        model_check=check,
        sufficiency=sufficiency(estimates, params, summaries, criteria),
        notes=notes,
        verdict=verdict,
        converged=converged,
        gaussian=gaussian,
        trials=trials,
        excluded=excluded,
        misfit=misfit,
    )


def fit_joint(
    groups: Sequence[TrialGroup], paper: PaperEstimate, cox_reid: bool = True
) -> JointFit:
    """The maximum-likelihood fit (Cox-Reid adjusted by default) from the
    paper-method start."""
    return joint_estimate(groups, joint_start(paper), cox_reid=cox_reid)


def trial_number(observation: Observation, index: int) -> int:
    """The trial's number: its own, else its 1-based position in the input."""
    return observation.trial if observation.trial is not None else index + 1


def leave_out(
    observations: Sequence[Observation], exclude: Iterable[int]
) -> tuple[list[Observation], tuple[int, ...]]:
    """The trials not excluded, and the excluded numbers (sorted).

    Raises:
        MeasurementError: a number that is no trial's (the message lists the
            trials' range).
    """
    wanted = sorted(set(int(t) for t in exclude))
    numbers = [trial_number(o, i) for i, o in enumerate(observations)]
    missing = [t for t in wanted if t not in numbers]
    if missing:
        span = f"{min(numbers)}..{max(numbers)}" if numbers else "none"
        raise MeasurementError(
            f"no trial numbered {', '.join(str(t) for t in missing)} to exclude "
            f"(the trials are numbered {span})"
        )
    kept = [o for o, t in zip(observations, numbers, strict=True) if t not in wanted]
    return kept, tuple(wanted)


def _numbered(observations: Sequence[Observation]) -> list[Observation]:
    return [
        o if o.trial is not None else replace(o, trial=i + 1) for i, o in enumerate(observations)
    ]


_MEMO_SIZE = 16
"""Estimates kept by :func:`estimate` for repeated calls on the same trials."""
_memo: ResultMemo[EstimateResult] = ResultMemo(_MEMO_SIZE)


def _memo_key(
    observations: Sequence[Observation],
    method: str,
    criteria: Criteria | None,
    exclude: tuple[int, ...],
    ambiguous: tuple[int, ...],
    turns_exact: bool,
) -> Hashable:
    """Everything :func:`estimate` reads, as a hashable value (arrays by their bytes)."""
    trials = tuple(
        (
            o.design,
            o.pose_change.shape,
            o.pose_change.tobytes(),
            o.measurement_cov.shape,
            o.measurement_cov.tobytes(),
            o.line,
            o.trial,
        )
        for o in observations
    )
    return (trials, method, criteria, exclude, ambiguous, turns_exact)


def estimate(
    observations: Sequence[Observation],
    method: Method = "robust",
    criteria: Criteria | None = None,
    exclude: Iterable[int] = (),
    ambiguous: Sequence[int] = (),
    turns_exact: bool = True,
) -> EstimateResult:
    """Estimate the four parameters from trials.

    The same trials with the same arguments give the same (immutable) result:
    the last :data:`_MEMO_SIZE` results are kept, so a process that estimates
    one session again (the test suite's commands in one process, a library
    caller's report and export) computes it once.

    Args:
        observations: the trials (any mix of designs).
        method: ``robust`` (the default: Gaussian with a per-trial outlier
            probability, Cox-Reid adjusted), ``joint`` (Gaussian maximum
            likelihood, Cox-Reid adjusted) or ``paper`` (the sequential
            method of moments).
        criteria: precision targets of the sufficiency check.
        exclude: trial numbers to leave out (a view: nothing is deleted).
        ambiguous: trial numbers the caller already left out as ambiguous
            (they make the verdict doubtful).
        turns_exact: False for a robot whose in-place turns carry error
            (``[robot] turns_exact``): its ``turn`` trials make the verdict doubtful.

    Raises:
        MeasurementError: too few trials, no design that identifies E_R, or
            an excluded number that is no trial's.
    """
    excluded, ambiguous_numbers = tuple(exclude), tuple(ambiguous)
    key = _memo_key(observations, method, criteria, excluded, ambiguous_numbers, turns_exact)
    return _memo.get(
        key,
        lambda: _estimate(observations, method, criteria, excluded, ambiguous_numbers, turns_exact),
    )


def _estimate(
    observations: Sequence[Observation],
    method: Method,
    criteria: Criteria | None,
    exclude: Iterable[int],
    ambiguous: Sequence[int],
    turns_exact: bool,
) -> EstimateResult:
    """:func:`estimate` without the memo."""
    if method not in METHODS:
        raise MeasurementError(f"method must be one of {METHODS}, got {method!r}")
    observations, excluded = leave_out(_numbered(observations), exclude)
    backward = [o.design.backward for o in observations]
    observations = [forward_view(o) for o in observations]
    if not observations:
        raise MeasurementError("no trials to estimate from")
    groups = group_trials(observations)
    summaries = summarise(groups)
    paper = paper_estimate(summaries)
    ml = fit_joint(groups, paper)
    common = {
        "excluded": excluded,
        "ambiguous": ambiguous,
        "check_params": ml.params,
        "turns_exact": turns_exact,
        "backward": backward,
    }
    if method == "paper":
        return build_result(
            "paper",
            observations,
            summaries,
            paper.params,
            paper.covariance,
            (*paper_notes(paper), "model check at the joint maximum-likelihood fit"),
            criteria,
            check_covariance=ml.covariance,
            **common,  # type: ignore[arg-type]
        )
    state = f"converged in {ml.iterations} steps" if ml.converged else "DID NOT CONVERGE"
    if method == "joint":
        notes = (f"joint maximum likelihood (Cox-Reid adjusted), paper-method start: {state}",)
        unweighted = np.ones(len(observations))
        ratio = sandwich_ratio(*trial_scores(observations, ml.point.phi, unweighted))
        return build_result(
            "joint",
            observations,
            summaries,
            ml.params,
            ml.covariance,
            notes,
            criteria,
            converged=ml.converged,
            intervals=honest_estimates(groups, ml, ratio),
            **common,  # type: ignore[arg-type]
        )
    rob = robust_fit(observations, groups, ml)
    named = [int(i) for i in np.flatnonzero(rob.clean_probability < OUTLIER_WEIGHT)]
    weights = rob.clean_probability + (1.0 - rob.clean_probability) / INFLATION
    gaussian, _ = _estimates(ml.params, ml.covariance, len(observations))
    diagnostics = tuple(
        TrialDiagnostic(
            trial_number(o, i),
            o.design.label(),
            float(rob.clean_probability[i]),
            (
                float(rob.influence[i, 0]),
                float(rob.influence[i, 1]),
                float(rob.influence[i, 2]),
                float(rob.influence[i, 3]),
            ),
        )
        for i, o in enumerate(observations)
    )
    notes = (
        f"robust maximum likelihood (outlier probability {EPSILON:g} per trial, Cox-Reid "
        f"adjusted): {rob.em_iterations} EM steps from the Gaussian fit ({state})",
    )
    return build_result(
        "robust",
        observations,
        summaries,
        rob.fit.params,
        rob.fit.covariance,
        notes,
        criteria,
        check_params=rob.fit.params,
        named_outliers=named,
        converged=rob.converged and ml.converged,
        gaussian=gaussian,
        trials=diagnostics,
        excluded=excluded,
        ambiguous=ambiguous,
        intervals=honest_estimates(
            weighted_groups(observations, weights, {g.design: g.reference for g in groups}),
            rob.fit,
            sandwich_ratio(rob.scores, rob.information),
        ),
        turns_exact=turns_exact,
        backward=backward,
    )
