"""One call from trials to an :class:`EstimateResult`, by either method."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Literal

import numpy as np

from odohil.errors import MeasurementError
from odohil.science.estimators.checks import Criteria, model_check, sufficiency
from odohil.science.estimators.joint import JointFit, joint_estimate, start_phi
from odohil.science.estimators.observations import (
    DesignSummary,
    Observation,
    TrialGroup,
    group_trials,
    summarise,
)
from odohil.science.estimators.paper import PaperEstimate, paper_estimate
from odohil.science.estimators.result import EstimateResult, ParameterEstimate
from odohil.science.parameters import PARAMETER_NAMES, ErrorParameters
from odohil.science.paths import FloatArray

Method = Literal["joint", "paper"]
METHODS: tuple[Method, ...] = ("joint", "paper")


def paper_notes(paper: PaperEstimate) -> tuple[str, ...]:
    """Which designs gave which parameters."""
    return (
        f"E_R, K_theta, E_T from {paper.first.design.label()} ({paper.first.n} trials); "
        f"K_rho from {paper.second.design.label()} ({paper.second.n} trials)",
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


def build_result(
    method: str,
    observations: Sequence[Observation],
    summaries: Sequence[DesignSummary],
    params: ErrorParameters,
    covariance: FloatArray,
    notes: tuple[str, ...],
    criteria: Criteria | None = None,
) -> EstimateResult:
    """Assemble the result and run both checks."""
    cov = np.array(covariance, dtype=np.float64)
    stderr = np.sqrt(np.where(np.isfinite(np.diag(cov)), np.clip(np.diag(cov), 0.0, None), np.inf))
    estimates = tuple(
        ParameterEstimate.build(name, value, float(se))
        for name, value, se in zip(PARAMETER_NAMES, params.as_tuple(), stderr, strict=True)
    )
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov / np.outer(stderr, stderr)
    corr[~np.isfinite(corr)] = math.nan
    np.fill_diagonal(corr, 1.0)
    return EstimateResult(
        method=method,
        n_trials=len(observations),
        params=params,
        parameters=estimates,
        covariance=tuple(tuple(float(v) for v in row) for row in cov),
        correlation=tuple(tuple(float(v) for v in row) for row in corr),
        model_check=model_check(observations, params),
        sufficiency=sufficiency(estimates, params, summaries, criteria),
        notes=notes,
    )


def fit_joint(groups: Sequence[TrialGroup], paper: PaperEstimate) -> JointFit:
    """The maximum-likelihood fit from the paper-method start."""
    return joint_estimate(groups, joint_start(paper))


def estimate(
    observations: Sequence[Observation],
    method: Method = "joint",
    criteria: Criteria | None = None,
) -> EstimateResult:
    """Estimate the four parameters from trials.

    Args:
        observations: the trials (any mix of designs).
        method: ``joint`` (maximum likelihood, the default) or ``paper``
            (the sequential method of moments).
        criteria: precision targets of the sufficiency check.

    Raises:
        MeasurementError: too few trials, or no design that identifies E_R.
    """
    if method not in METHODS:
        raise MeasurementError(f"method must be one of {METHODS}, got {method!r}")
    if not observations:
        raise MeasurementError("no trials to estimate from")
    groups = group_trials(observations)
    summaries = summarise(groups)
    paper = paper_estimate(summaries)
    if method == "paper":
        return build_result(
            "paper",
            observations,
            summaries,
            paper.params,
            paper.covariance,
            paper_notes(paper),
            criteria,
        )
    fit = fit_joint(groups, paper)
    notes = (
        "joint maximum likelihood from the paper-method start: "
        + (f"converged in {fit.iterations} steps" if fit.converged else "DID NOT CONVERGE"),
    )
    return build_result(
        "joint", observations, summaries, fit.params, fit.covariance, notes, criteria
    )
