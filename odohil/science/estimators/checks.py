"""The model check and the sufficiency check of an estimate.

Model check: with the fitted parameters, each trial's pose change should be a
draw from N(mu_d, Sigma_d + C_i). Its squared Mahalanobis distance is then
chi^2(3); a trial beyond the 1 % level after a Bonferroni correction for n
trials is an outlier, and the sum over trials, chi^2(3n - 4) approximately, gives
an overall goodness-of-fit p-value.

Sufficiency check: a parameter is identified when its standard error meets a
target (:class:`Criteria`). For each one that does not, the Fisher information
of one more trial of each design in the data
(:func:`odohil.science.fisher.fisher_information`) tells how many more trials
of that design would get it there: the result's standard error is scaled by
sqrt([(I + m I_d)^-1]_pp / [I^-1]_pp), so an inefficient estimator (the paper's
method) keeps its inefficiency.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from odohil import units
from odohil.errors import ParameterError
from odohil.science import distributions
from odohil.science.estimators.likelihood import design_path
from odohil.science.estimators.misfit import MisfitCheck, TrialLabel, misfit_check
from odohil.science.estimators.observations import DesignSummary, Observation
from odohil.science.estimators.paper import MIN_START_TRIALS, START_NEEDS, starts_estimate
from odohil.science.estimators.result import (
    ModelCheck,
    Outlier,
    ParameterEstimate,
    Sufficiency,
    Suggestion,
)
from odohil.science.fisher import (
    MomentDerivatives,
    fisher_information,
    moment_derivatives,
    trial_information,
)
from odohil.science.grouping import by_design
from odohil.science.moments import PoseMoments, pose_moments
from odohil.science.parameters import PARAMETER_NAMES, ErrorParameters
from odohil.science.paths import Design, FloatArray
from odohil.science.targets import TARGET_FLOORS, TARGET_FRACTIONS
from odohil.science.validation import predict_path

OUTLIER_LEVEL = 0.01
"""Family-wise level of the outlier test (Bonferroni over the trials)."""
FIT_LEVEL = 0.01
"""Level of the overall goodness-of-fit test."""
MAX_EXTRA_TRIALS = 100_000


@dataclass(frozen=True)
class Criteria:
    """Precision targets of the sufficiency check.

    Defaults: :mod:`odohil.science.targets` (the planner's default targets).

    Attributes:
        e_r_relative: largest stderr / |E_R|.
        e_r_floor: stderr of E_R always accepted, rad/m (E_R may be 0).
        e_t_relative: largest stderr / |E_T| (a fixed +-0.05 let
            E_T -0.017 +- 0.015 pass as known).
        e_t_floor: stderr of E_T always accepted (E_T may be 0).
        k_relative: largest stderr / K for K_theta and K_rho.
    """

    e_r_relative: float = TARGET_FRACTIONS["E_R"]
    e_r_floor: float = TARGET_FLOORS["E_R"]
    e_t_relative: float = TARGET_FRACTIONS["E_T"]
    e_t_floor: float = TARGET_FLOORS["E_T"]
    k_relative: float = TARGET_FRACTIONS["K_theta"]

    def targets(self, params: ErrorParameters) -> FloatArray:
        """Largest acceptable stderr of each parameter, SI."""
        return np.array(
            [
                max(self.e_r_relative * abs(params.e_r), self.e_r_floor),
                max(self.e_t_relative * abs(params.e_t), self.e_t_floor),
                self.k_relative * params.k_theta,
                self.k_relative * params.k_rho,
            ]
        )


def mahalanobis2(
    observations: Sequence[Observation],
    params: ErrorParameters,
    moments: Mapping[Design, PoseMoments] | None = None,
) -> FloatArray:
    """Each trial's squared Mahalanobis distance from the model (Delta residual
    taken modulo 2 pi); vectorised per design. ``moments``: the model's
    moments of each design at ``params``, if the caller has them."""
    out = np.empty(len(observations))
    trials = by_design(range(len(observations)), lambda i: observations[i].design)
    for design, index in trials.items():
        m = pose_moments(design_path(design), params) if moments is None else moments[design]
        poses = np.array([observations[i].pose_change for i in index])
        resid = poses - m.mean
        resid[:, 2] = units.wrap_angles(resid[:, 2])
        total = m.cov + np.array([observations[i].measurement_cov for i in index])
        total = 0.5 * (total + np.swapaxes(total, 1, 2))
        try:
            solved = np.linalg.solve(total, resid[:, :, None])[:, :, 0]
        except np.linalg.LinAlgError:
            solved = np.array(
                [np.linalg.lstsq(c, r, rcond=1e-15)[0] for c, r in zip(total, resid, strict=True)]
            )
        out[index] = np.einsum("ni,ni->n", resid, solved)
    return out


def model_check(
    observations: Sequence[Observation],
    params: ErrorParameters,
    named: Sequence[int] = (),
) -> ModelCheck:
    """The model check of ``params`` against the trials (see the module docstring).

    ``named``: input positions the robust fit already named outliers; they
    are outliers whatever their distance, and left out of the overall test.
    """
    return distance_check(
        mahalanobis2(observations, params),
        [(o.line, o.trial, o.design.label()) for o in observations],
        named,
    )


def distance_check(
    d2: FloatArray,
    labels: Sequence[tuple[int | None, int | None, str]],
    named: Sequence[int] = (),
    n_params: int = 4,
) -> ModelCheck:
    """The model check from each trial's squared Mahalanobis distance ``d2``
    (chi^2(3) under the model), any model: ``labels`` per trial (line, trial
    number, design or path label), ``named`` as in :func:`model_check`, and
    ``n_params`` fitted parameters (the overall test has 3 n - n_params
    degrees of freedom)."""
    n = len(d2)
    p_each = distributions.chi2_sf_each(d2, 3)  # chi^2(3) tail
    flagged = sorted(set(int(j) for j in np.flatnonzero(p_each < OUTLIER_LEVEL / n)) | set(named))
    outliers = tuple(
        Outlier(
            i,
            labels[i][0],
            float(d2[i]),
            float(p_each[i]),
            labels[i][1],
            labels[i][2],
        )
        for i in flagged
    )
    kept = np.ones(n, dtype=bool)
    kept[list(named)] = False
    dof = max(1, 3 * int(kept.sum()) - n_params)
    chi2 = float(d2[kept].sum())
    p_value = distributions.chi2_sf(chi2, dof)
    if outliers:
        named_labels = [o.label() for o in outliers]
        verb = "are outliers" if len(named_labels) > 1 else "is an outlier"
        verdict = (
            f"{units.join_words(named_labels)} {verb}: the model puts them beyond its "
            f"{100 * (1 - OUTLIER_LEVEL):g} % range (check the marks, or the run)"
        )
    elif p_value < FIT_LEVEL:
        verdict = (
            f"the data do not fit the model (goodness-of-fit p = {p_value:.2g}), "
            "though no single trial stands out"
        )
    else:
        verdict = f"the data fit the model (goodness-of-fit p = {p_value:.2g})"
    return ModelCheck(
        fits=not outliers and p_value >= FIT_LEVEL,
        verdict=verdict,
        chi2=chi2,
        dof=dof,
        p_value=p_value,
        outliers=outliers,
        mahalanobis2=tuple(float(v) for v in d2),
    )


_MIRROR = np.diag([-1.0, 1.0, -1.0])
FORTH_BACK_TURN_HINT = (
    "if the robot is a differential drive its spins carry error: set turns_exact = false "
    "and calibrate with variant=reverse"
)
"""The advice on a bias of forth-and-back ``turn`` trials."""


def design_misfit(
    observations: Sequence[Observation],
    params: ErrorParameters,
    covariance: FloatArray | None,
    backward: Sequence[bool] | None = None,
    *,
    turn_hint: str = FORTH_BACK_TURN_HINT,
) -> MisfitCheck:
    """The misfit checks (:mod:`odohil.science.estimators.misfit`) of
    forth-and-back trials at the fitted ``params``.

    ``observations`` are as the estimators model them (a backward trial as its
    forward design's mirror image); ``backward`` says which were driven
    backwards (default: from their designs). Their residuals are mirrored back,
    so a bias is reported in the frame the trial was driven in. Groups: the
    design (forward label) by direction (forward/backward); the trial-order
    check compares the first trial of each design and direction with the rest.
    ``covariance``: the estimate's 4 x 4 covariance (SI) for the parameter term,
    or None.
    """
    n = len(observations)
    flags = list(backward) if backward is not None else [o.design.backward for o in observations]
    residuals = np.empty((n, 3))
    covs = np.empty((n, 3, 3))
    jacobians = np.empty((n, 3, 4))
    labels: list[TrialLabel] = []
    trials = by_design(range(n), lambda i: observations[i].design)
    for design, index in trials.items():
        prediction = predict_path(design_path(design), params)
        for i in index:
            r = observations[i].pose_change - prediction.mean
            r[2] = units.wrap_angle(float(r[2]))
            v = prediction.cov + observations[i].measurement_cov
            j = prediction.jacobian
            if flags[i] != design.backward:
                r, v, j = _MIRROR @ r, _MIRROR @ v @ _MIRROR, _MIRROR @ j
            residuals[i], covs[i], jacobians[i] = r, v, j
    for i, o in enumerate(observations):
        design = o.design.forward
        labels.append(
            TrialLabel(
                design.label(),
                "backward" if flags[i] else "forward",
                turns=design.variant == "turn",
            )
        )
    return misfit_check(
        residuals,
        covs,
        labels,
        jacobians,
        covariance,
        fitted=True,
        turn_hint=turn_hint,
    )


def _variances(info: FloatArray) -> FloatArray:
    """diag(I^-1), inf for parameters the information does not determine."""
    out = np.full(4, math.inf)
    ok = info.diagonal() > 0
    if ok.all():
        sub = info
    elif ok.any():
        sub = info[np.ix_(ok, ok)]
    else:
        return out
    scale = np.sqrt(sub.diagonal())
    scaled = sub / (scale[:, None] * scale)
    eigen = np.linalg.eigvalsh(scaled)
    if eigen[0] > 1e-12 * eigen[-1]:
        out[ok] = np.linalg.inv(scaled).diagonal() / scale**2
    return out


def _information(
    summaries: Sequence[DesignSummary], params: ErrorParameters
) -> tuple[FloatArray, dict[Design, FloatArray]]:
    """Total information of the data and per-trial information of each design, SI.

    The model's derivatives are taken at the parameters rounded to 3
    significant digits (:func:`_derivatives_near`): the advice does not need
    more, and a live session's estimate then reuses them across updates (they
    cost more than the rest of a live update)."""
    per_trial = {
        s.design: trial_information(_derivatives_near(s.design, params), s.measurement_cov)
        for s in summaries
    }
    total = sum((s.n * per_trial[s.design] for s in summaries), np.zeros((4, 4)))
    return total, per_trial


def _derivatives_near(design: Design, params: ErrorParameters) -> MomentDerivatives:
    rounded = tuple(float(f"{v:.3g}") for v in params.as_tuple())
    return _cached_derivatives(design, rounded)


@lru_cache(maxsize=64)
def _cached_derivatives(design: Design, values: tuple[float, ...]) -> MomentDerivatives:
    return moment_derivatives(design_path(design), ErrorParameters(*values))


def _extra_trials(
    info: FloatArray,
    one: FloatArray,
    ratio_base: FloatArray,
    stderr: FloatArray,
    targets: FloatArray,
    flagged: list[int],
) -> int | None:
    """Fewest m with every flagged stderr, scaled by the information ratio, on target."""

    def ok(m: int) -> bool:
        var = _variances(info + m * one)
        for p in flagged:
            if not math.isfinite(var[p]):
                return False
            if math.isfinite(ratio_base[p]) and math.isfinite(stderr[p]):
                predicted = stderr[p] * math.sqrt(var[p] / ratio_base[p])
            else:
                predicted = math.sqrt(var[p])
            if predicted > targets[p]:
                return False
        return True

    high = 1
    while not ok(high):
        high *= 2
        if high > MAX_EXTRA_TRIALS:
            return None
    low = high // 2
    while high - low > 1:
        mid = (low + high) // 2
        if ok(mid):
            high = mid
        else:
            low = mid
    return high


def sufficiency(
    estimates: Sequence[ParameterEstimate],
    params: ErrorParameters,
    summaries: Sequence[DesignSummary],
    criteria: Criteria | None = None,
) -> Sufficiency:
    """Which parameters miss their precision target, and what would fix that."""
    criteria = criteria or Criteria()
    targets = criteria.targets(params)
    stderr = np.array([e.stderr for e in estimates])
    flagged: list[int] = []
    reasons: list[str] = []
    for p, name in enumerate(PARAMETER_NAMES):
        value = estimates[p].value
        if not math.isfinite(stderr[p]):
            flagged.append(p)
            reasons.append(f"{name} is not identifiable from these trials (no information)")
        elif name in ("K_theta", "K_rho") and value < 2.0 * stderr[p]:
            flagged.append(p)
            # aim at pinning it to within the target relative to its current upper reach
            targets[p] = criteria.k_relative * (value + 2.0 * stderr[p])
            reasons.append(
                f"{name} is not distinguishable from zero (estimate {value:.2g}, "
                f"standard error {stderr[p]:.2g})"
            )
        elif stderr[p] > targets[p]:
            flagged.append(p)
            if name == "E_T":
                reasons.append(
                    f"E_T has standard error {stderr[p]:.2g} (target {targets[p]:.2g}); "
                    "closed paths pin E_T only weakly, about as 1/|E_R|; one-way runs (k=0.5) "
                    "pin it far better"
                )
            elif abs(value) < 1e-300:  # no relative error to speak of (a frozen measurement)
                reasons.append(
                    f"{name} has standard error {stderr[p]:.2g} (target {targets[p]:.2g}); "
                    "its estimate is 0, so no relative error"
                )
            else:
                reasons.append(
                    f"{name} has relative standard error {stderr[p] / abs(value):.0%} "
                    f"(target {targets[p] / abs(value):.0%})"
                )
    if not flagged:
        return Sufficiency(True, "enough trials: every parameter meets its target", (), (), ())
    names = tuple(PARAMETER_NAMES[p] for p in flagged)
    try:
        info, per_trial = _information(summaries, params)
    except ParameterError:
        info, per_trial = np.zeros((4, 4)), {}
    base = _variances(info)
    suggestions: list[Suggestion] = []
    advice: list[str] = []
    for p in flagged:
        mine: list[Suggestion] = []
        for summary in summaries:
            one = per_trial.get(summary.design)
            more = (
                _extra_trials(info, one, base, stderr, targets, [p])
                if one is not None and targets[p] > 0
                else None
            )
            d = summary.design
            mine.append(Suggestion(PARAMETER_NAMES[p], d.label(), d.k, d.l_m, d.variant, more))
        suggestions += mine
        doable = [s for s in mine if s.more_trials is not None]
        if doable:
            best = min(doable, key=lambda s: (s.more_trials or 0) * s.l_m * 2 * s.k)
            advice.append(
                f"{PARAMETER_NAMES[p]}: about "
                f"{units.plural(best.more_trials or 0, 'more trial')} of {best.design_label}"
            )
        else:
            advice.append(f"{PARAMETER_NAMES[p]}: more trials of these designs would not do")
    verdict = f"not enough trials for {units.join_words(list(names))} ({'; '.join(advice)})"
    return Sufficiency(False, verdict, names, tuple(reasons), tuple(suggestions))


def plan_problems(
    designs: Sequence[tuple[Design, int]], params: ErrorParameters
) -> tuple[str, ...]:
    """Why trials of these designs, this many each, cannot give an estimate of the
    four parameters, known before any is driven (empty when they can): every
    estimator starts from the paper's method
    (:func:`odohil.science.estimators.paper.starts_estimate`), and every
    parameter needs information (:func:`odohil.science.fisher.fisher_information`
    at ``params``, exact poses: measurement noise only lowers it). Each reason
    says what would make the plan estimable. Backward trials count for their
    forward design (the estimators mirror them)."""
    counts: dict[Design, int] = {}
    for design, n in designs:
        counts[design.forward] = counts.get(design.forward, 0) + n
    labels = [f"{d.label()}: {units.plural(n, 'trial')}" for d, n in counts.items()]
    if not any(starts_estimate(d, n) for d, n in counts.items()):
        signed = [d for d in counts if abs(d.path().signed_distance_m) > 0.0]
        if signed:
            fix = "; ".join(f"n={MIN_START_TRIALS} or more for {d.label()}" for d in signed)
        else:
            fix = (
                f"add {MIN_START_TRIALS} or more trials of a design that ends away from its "
                "start: an odd number of legs (k=0.5, 1.5, ...; e.g. k=0.5,l=1,n="
                f"{MIN_START_TRIALS}), or variant=turn on a robot whose turns are exact"
            )
        return (
            "every estimate starts from the paper's method, which needs "
            f"{START_NEEDS}; the plan has {units.join_words(labels)} (signed distance "
            + ", ".join(f"{d.path().signed_distance_m:g} m" for d in counts)
            + f"). It becomes estimable with: {fix}",
        )
    try:
        variances = _variances(fisher_information(list(counts.items()), params))
    except (ParameterError, np.linalg.LinAlgError):
        return ()  # not computable at these values (K = 0 with exact poses): no finding
    missing = [PARAMETER_NAMES[p] for p in range(4) if not math.isfinite(variances[p])]
    if missing:
        return (
            f"{units.join_words(missing)} cannot be identified from "
            f"{units.join_words(labels)} (no Fisher information); add a design of another k or l",
        )
    return ()
