"""The robust fit: a Gaussian with a per-trial outlier probability.

Each trial's v is modelled as the mixture

    (1 - EPSILON) N(mu_d, S_d) + EPSILON N(mu_d, INFLATION S_d),  S_d = Sigma_d + C_i

so a trial the model cannot explain (a typo in a distance, a slipped wheel) is
absorbed by the broad component instead of dragging K_theta and K_rho up to
explain it. The fit is EM: the E-step gives each trial's probability r_i of
the clean component from its squared Mahalanobis distance q_i,

    r_i = 1 / (1 + EPSILON / (1 - EPSILON) INFLATION^-3/2 exp(q_i/2 (1 - 1/INFLATION)))

and the M-step maximises the Gaussian likelihood with weights
w_i = r_i + (1 - r_i) / INFLATION on the trials' residuals (one Fisher-scoring
fit, Cox-Reid adjusted, warm-started). On clean data r_i is 1 to within 1e-4
up to q_i of about 15 (chi^2(3) tail 0.2 %), so the fit is the Gaussian one;
a trial at q_i = 23 or more gets half weight or less. The covariance is the
inverse of the weighted expected information (outliers contribute nothing).

Per-trial influence: how far leaving trial i out moves each parameter, in its
standard errors, by one Newton step from the fit: I^-1 g_i, with g_i the
trial's (weighted) score.

The EM works on any trials behind the small :class:`RobustTrials` interface
(:func:`robust_em`): the trials of forth-and-back designs here
(:func:`robust_fit`), general-path trials in
:mod:`odohil.science.estimators.paths`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property
from typing import Protocol

import numpy as np

from odohil.science.estimators.checks import mahalanobis2
from odohil.science.estimators.joint import JointFit, refine
from odohil.science.estimators.likelihood import GroupStats
from odohil.science.estimators.observations import Observation, TrialGroup
from odohil.science.estimators.scores import trial_scores
from odohil.science.moments import pose_moments
from odohil.science.parameters import ErrorParameters
from odohil.science.paths import Design, FloatArray

EPSILON = 0.01
"""Prior probability that a trial is an outlier."""
INFLATION = 100.0
"""Variance factor of the outlier component (standard deviations 10 times the model's)."""
OUTLIER_WEIGHT = 0.5
"""A trial whose clean-component probability falls below this is named an outlier."""
_RESTART_D2 = 7.8
"""Restart without the farthest trial when its squared distance exceeds this
(chi^2(3) 95 % point)."""
_MAX_EM = 40
_EM_TOLERANCE = 1e-4
"""EM stops when no parameter moves more than this many standard errors."""


@dataclass(frozen=True)
class RobustFit:
    """The robust fit.

    Attributes:
        fit: the weighted, Cox-Reid adjusted fit at convergence.
        clean_probability: per trial (input order), the probability of the
            clean component, r_i.
        influence: (n, p) per trial, the change of each parameter (SI order
            E_R, E_T, K_theta, K_rho, then the layout's others) when it is
            left out, in standard errors.
        scores: (n, p) per trial, its weighted score in phi at the fit
            (odohil/science/estimators/scores.py).
        information: (p, p) the weighted expected information in phi at the fit.
        em_iterations: EM iterations taken.
        converged: EM and the last M-step both converged.
    """

    fit: JointFit
    clean_probability: FloatArray
    influence: FloatArray
    scores: FloatArray
    information: FloatArray
    em_iterations: int
    converged: bool


def clean_probability(d2: FloatArray) -> FloatArray:
    """r_i from the squared Mahalanobis distances (see the module docstring)."""
    log_ratio = (
        math.log(EPSILON / (1.0 - EPSILON))
        - 1.5 * math.log(INFLATION)
        + 0.5 * (1.0 - 1.0 / INFLATION) * np.asarray(d2, dtype=np.float64)
    )
    result: FloatArray = 1.0 / (1.0 + np.exp(np.minimum(log_ratio, 700.0)))
    return result


def weighted_groups(
    observations: Sequence[Observation], weights: FloatArray, references: dict[Design, float]
) -> list[TrialGroup]:
    """One group per design and measurement covariance, trials weighted."""
    return _GroupLayout.of(observations, references).groups(weights)


@dataclass(frozen=True)
class _GroupLayout:
    """The weight-free part of :func:`weighted_groups` (which trials go in
    which group, their unwrapped pose changes and outer products, the sums of
    their measurement covariances), so that the EM's M-steps only weight and
    sum. The sums run over the trials in order, as ``TrialGroup.add`` would."""

    designs: tuple[Design, ...]
    references: tuple[float, ...]
    indices: tuple[list[int], ...]
    poses: tuple[FloatArray, ...]
    outers: tuple[FloatArray, ...]
    measurement_totals: tuple[FloatArray, ...]

    @staticmethod
    def of(observations: Sequence[Observation], references: dict[Design, float]) -> _GroupLayout:
        members: dict[tuple[Design, bytes], list[int]] = {}
        for i, obs in enumerate(observations):
            members.setdefault((obs.design, obs.measurement_cov.tobytes()), []).append(i)
        designs, refs, indices, poses, outers, totals = [], [], [], [], [], []
        for (design, _), index in members.items():
            group = TrialGroup(design, references[design])
            v = np.array([group.unwrapped(observations[i].pose_change) for i in index])
            measurement_total = np.zeros((3, 3))
            for i in index:
                measurement_total = measurement_total + observations[i].measurement_cov
            designs.append(design)
            refs.append(group.reference)
            indices.append(index)
            poses.append(v)
            outers.append(v[:, :, None] * v[:, None, :])
            totals.append(measurement_total)
        return _GroupLayout(
            tuple(designs), tuple(refs), tuple(indices), tuple(poses), tuple(outers), tuple(totals)
        )

    def groups(self, weights: FloatArray) -> list[TrialGroup]:
        """The groups with ``weights`` (one per trial) on the residuals."""
        w_all = np.asarray(weights, dtype=np.float64)
        out: list[TrialGroup] = []
        for design, reference, index, v, outer, measurement_total in zip(
            self.designs,
            self.references,
            self.indices,
            self.poses,
            self.outers,
            self.measurement_totals,
            strict=True,
        ):
            w = w_all[index]
            weight = 0.0
            for value in w.tolist():
                weight += value
            # running sums from 0 in trial order (accumulate is sequential)
            total = np.add.accumulate(np.concatenate([np.zeros((1, 3)), w[:, None] * v]), axis=0)[
                -1
            ].copy()
            outer_total = np.add.accumulate(
                np.concatenate([np.zeros((1, 3, 3)), w[:, None, None] * outer]), axis=0
            )[-1].copy()
            out.append(
                TrialGroup(
                    design,
                    reference,
                    len(index),
                    total,
                    outer_total,
                    measurement_total.copy(),
                    weight,
                )
            )
        return out


def _references(groups: Sequence[TrialGroup]) -> dict[Design, float]:
    out: dict[Design, float] = {}
    for g in groups:
        out.setdefault(g.design, g.reference)
    return out


def mixture_nll(observations: Sequence[Observation], params: ErrorParameters) -> float:
    """Negative log-likelihood of the mixture at ``params`` (constants dropped)."""
    log_det: dict[tuple[Design, bytes], float] = {}
    moments = {}
    for obs in observations:
        if obs.design not in moments:
            moments[obs.design] = pose_moments(obs.design.path(), params)
    d2 = mahalanobis2(observations, params, moments)
    for obs in observations:
        key = (obs.design, obs.measurement_cov.tobytes())
        if key not in log_det:
            cov = moments[obs.design].cov + obs.measurement_cov
            sign, value = np.linalg.slogdet(0.5 * (cov + cov.T))
            log_det[key] = value if sign > 0 else math.inf
    dets = np.array([log_det[(o.design, o.measurement_cov.tobytes())] for o in observations])
    return mixture_terms(d2, dets)


class RobustTrials(Protocol):
    """What the EM needs of a set of trials."""

    def __len__(self) -> int:
        """Number of trials."""
        ...

    def distances(self, fit: JointFit) -> FloatArray:
        """Each trial's squared Mahalanobis distance from the model at ``fit``."""
        ...

    def groups(self, weights: FloatArray) -> Sequence[GroupStats]:
        """The trials as likelihood groups, residuals weighted."""
        ...

    def scores(self, fit: JointFit, weights: FloatArray) -> tuple[FloatArray, FloatArray]:
        """(n, p) weighted scores and (p, p) weighted information at ``fit``."""
        ...

    def mixture_nll(self, fit: JointFit) -> float:
        """Negative log-likelihood of the mixture at ``fit`` (constants dropped)."""
        ...


@dataclass(frozen=True)
class _DesignTrials:
    """Trials of forth-and-back designs as :class:`RobustTrials`."""

    observations: Sequence[Observation]
    references: dict[Design, float]

    def __len__(self) -> int:
        return len(self.observations)

    def distances(self, fit: JointFit) -> FloatArray:
        return mahalanobis2(self.observations, fit.params)

    @cached_property
    def _layout(self) -> _GroupLayout:
        return _GroupLayout.of(self.observations, self.references)

    def groups(self, weights: FloatArray) -> Sequence[GroupStats]:
        return self._layout.groups(weights)

    def scores(self, fit: JointFit, weights: FloatArray) -> tuple[FloatArray, FloatArray]:
        return trial_scores(self.observations, fit.point.phi, weights)

    def mixture_nll(self, fit: JointFit) -> float:
        return mixture_nll(self.observations, fit.params)


def mixture_terms(d2: FloatArray, log_det: FloatArray) -> float:
    """The mixture's negative log-likelihood from each trial's squared
    distance and log det of its covariance (constants dropped)."""
    q = np.asarray(d2, dtype=np.float64)
    clean = math.log1p(-EPSILON) - 0.5 * q
    broad = math.log(EPSILON) - 1.5 * math.log(INFLATION) - 0.5 * q / INFLATION
    return float((0.5 * np.asarray(log_det) - np.logaddexp(clean, broad)).sum())


def robust_fit(
    observations: Sequence[Observation], groups: Sequence[TrialGroup], start: JointFit
) -> RobustFit:
    """EM from ``start`` (the Gaussian fit of ``groups``, the unweighted trials);
    see :func:`robust_em`."""
    return robust_em(_DesignTrials(observations, _references(groups)), start)


def robust_em(trials: RobustTrials, start: JointFit) -> RobustFit:
    """EM from ``start`` (the Gaussian fit of the unweighted trials), and from
    the Gaussian fit without the trial farthest from it (a gross error can drag
    the Gaussian fit so far that it no longer stands out, above all at small
    n); the start whose EM ends at the lower mixture NLL wins."""
    d2 = trials.distances(start)
    best = _em(trials, start, d2)
    if len(trials) > 8 and float(d2.max()) > _RESTART_D2:
        worst = int(np.argmax(d2))
        weights = np.ones(len(trials))
        weights[worst] = 1.0 / INFLATION
        try:
            other = refine(trials.groups(weights), start.point, cox_reid=True)
            second = _em(trials, other)
        except (FloatingPointError, np.linalg.LinAlgError):
            return best
        if trials.mixture_nll(second.fit) < trials.mixture_nll(best.fit):
            return second
    return best


def _em(trials: RobustTrials, start: JointFit, start_d2: FloatArray | None = None) -> RobustFit:
    """EM from ``start`` (``start_d2``: the trials' distances from it, if known)."""
    fit = start
    r = np.ones(len(trials))
    converged = False
    iterations = 0
    for iterations in range(1, _MAX_EM + 1):
        d2 = trials.distances(fit) if iterations > 1 or start_d2 is None else start_d2
        r = clean_probability(d2)
        weights = r + (1.0 - r) / INFLATION
        new = refine(trials.groups(weights), fit.point, cox_reid=True)
        assert new.value.information is not None
        step = new.point.phi - fit.point.phi
        moved = math.sqrt(max(0.0, float(step @ new.value.information @ step)))
        fit = new
        if moved < _EM_TOLERANCE and new.converged:
            converged = True
            break
    weights = r + (1.0 - r) / INFLATION
    scores, information = trials.scores(fit, weights)
    return RobustFit(
        fit,
        r,
        influence(scores, information, fit),
        scores,
        information,
        iterations,
        converged and fit.converged,
    )


def influence(scores: FloatArray, information: FloatArray, fit: JointFit) -> FloatArray:
    """Per trial, I^-1 g_i in standard errors (see the module docstring), from
    the trials' scores and the information at ``fit``."""
    out = np.zeros(scores.shape)
    if not np.all(np.isfinite(fit.covariance)) or scores.shape[0] == 0:
        return out
    cov_phi = np.linalg.pinv(information)
    jac = fit.point.layout.jacobian(fit.point.phi)
    shift = (scores @ cov_phi.T) @ jac.T
    stderr = np.sqrt(np.clip(np.diag(jac @ cov_phi @ jac.T), 0.0, None))
    with np.errstate(divide="ignore", invalid="ignore"):
        out = np.where(stderr > 0, shift / stderr, 0.0)
    return out
