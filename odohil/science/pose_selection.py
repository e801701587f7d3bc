"""One pose-selection path for every source: candidates from the floor marks,
scored against the encoders and the model's predictive distribution, and the
operator-slip check.

Used the same way live (odohil/session/run/engine.py) and offline
(odohil/session/trials/trial_file.py); see docs/measurements.md.

1. **Predictive distribution** of one trial's pose change (dx m, dy m,
   dtheta rad): the model's moments (odohil/science/moments.py) at a
   :class:`ParameterBelief` (the current estimate, or the robot description's
   ``[priors]`` before there is one, or without them
   :data:`UNKNOWN_ROBOT_PAPER`), widened by the belief's parameter
   uncertainty (mean derivatives J: J^T Sigma J) and with the variance rates
   raised by one of their standard deviations (and never below the priors'
   values: an estimate from a few trials often puts K_theta near 0, and a
   prediction that tight would call clean trials slips); its mean is shifted by how far
   the encoders' end pose lies from the design's ideal encoder end pose (the
   motion's tolerance), so candidates are scored against the encoders too.
2. **Choice**: :func:`odohil.science.floor_marks.solve_marks` with that
   distribution as prior. The trial is **ambiguous** when a second candidate
   is within a likelihood ratio of
   :data:`odohil.science.floor_marks.CLEAR_CUT_LIKELIHOOD_RATIO` of the best
   AND lies more than :data:`AMBIGUITY_SEPARATION` standard deviations (of
   the chosen pose's covariance, in some component) away from it: two minima
   of one bent valley (small, near-identity motions) are not two answers.
3. **Slip check**: linearising the distances at the chosen pose x (Jacobian
   G, tape sigma s), the innovation of the distances against the prediction
   is v = (measured - d(x)) + G (x - mu), with covariance S = G P G^T + s^2 I
   (mu, P the predictive mean and covariance). T = v^T S^-1 v is chi^2 with m
   degrees of freedom for m clean distances; beyond its (1 - :data:`SLIP_LEVEL`)
   quantile the check trips. The suspect is the distance whose single
   outlier shift explains most of T: argmax_k (S^-1 v)_k^2 / (S^-1)_kk.
4. **Pose check** (:func:`pose_check`): the same test for a source that
   measures the pose itself (motion capture, a pose file, the fake's truth):
   the innovation is the pose against the prediction, v = x - mu, with
   covariance S = P + C (C the measurement's); beyond the same quantile the
   trial is doubtful, beyond :data:`IMPLAUSIBLE_SIGMAS` squared it is
   implausible. So is a pose whose distance from the start, or the farthest
   point of its path when the source saw the path, is less than half or more
   than twice the encoders' beyond :data:`SCALE_FLOOR_M` (and, above, beyond
   the prediction's spread): no odometry is that wrong, a frozen stream or
   a unit error is.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from functools import lru_cache

import numpy as np
import numpy.typing as npt

from odohil.errors import RobotDescriptionError
from odohil.science import distributions
from odohil.science.estimators.result import EstimateResult
from odohil.science.fisher import moment_derivatives
from odohil.science.floor_marks import (
    CLEAR_CUT_LIKELIHOOD_RATIO,
    MarkCandidate,
    MarkDistances,
    MarkSolution,
    PoseDistribution,
    PosePrior,
    distance_labels,
    linearised_marks,
    marks_from_pose,
    pose_covariance,
    solve_marks,
)
from odohil.science.moments import pose_moments, turn_errors_from
from odohil.science.parameters import PARAMETER_NAMES, ErrorParameters
from odohil.science.path_designs import PathDesign
from odohil.science.paths import Design
from odohil.science.robot_description import ParameterPriors, RobotDescription
from odohil.units import wrap_angle

FloatArray = npt.NDArray[np.float64]

SLIP_LEVEL = 1e-3
"""Level of the slip check: clean distances trip it about this rarely when
the predictive distribution is right (measured in tests/science/
test_pose_selection.py)."""
ESTIMATE_INFLATION = 2.0
"""An estimate's standard errors are widened by this factor before they
predict the next trial: a belief from few trials must not be overconfident."""
AMBIGUITY_SEPARATION = 5.0
"""Candidates closer than this many standard deviations of the chosen pose
(in every component) count as the same answer."""
IMPLAUSIBLE_SIGMAS = 10.0
"""A measured pose this many standard deviations (Mahalanobis, T = 100) from
the prediction is implausible: the measurement, not the robot, is wrong."""
SCALE_RATIO = 2.0
"""A measured distance from the start below 1/this or above this times the
encoders' is implausible (beyond :data:`SCALE_FLOOR_M`)."""
SCALE_FLOOR_M = 0.02
"""Distances from the start that differ by less than this are never
implausible, m (the noise of a farthest point seen in a noisy stream)."""
_LOG_AMBIGUOUS = math.log(CLEAR_CUT_LIKELIHOOD_RATIO)
UNKNOWN_ROBOT_PAPER: tuple[tuple[float, float], ...] = (
    (0.0, 2.0),
    (0.0, 0.05),
    (0.0, 1.0),
    (0.0, 1e-3),
)
"""Mean and standard deviation (deg/m, 1, deg^2/m, m) of the belief that
predicts a trial before there is an estimate when the robot description has
no ``[priors]``: any robot with E_R within +-2 deg/m, E_T within +-5 %,
K_theta up to 1 deg^2/m and K_rho up to 1e-3 m lies within one deviation
(the rates are raised by theirs), so its first clean trials do not trip the
slip check as a Nomad 150's prior made them (issue 31, bench/slip_check.py)."""

UNKNOWN_TURNS: tuple[tuple[str, float, float], ...] = (("e_turn", 0.0, 0.03), ("K_spin", 0.0, 1e-3))
"""The turn errors (name, mean, standard deviation; SI: e_turn no unit, K_spin
rad^2/rad) a robot whose turns are not exact (``turns_exact = false``: the
Create 2) is predicted with where no estimate pins them: a turn scale within
+-3 % (the fake Create 2's is 1.2 %) and K_spin up to 1e-3 (its 2e-4) lie
within one deviation. Predicted with exact turns, its first square is 2 pi
e_turn (0.075 rad at 1.2 %) off in heading without its spins' spread, and
trips the slip check on clean tape (issue 31, bench/slip_check_paths.py)."""


@dataclass(frozen=True, eq=False)
class ParameterBelief:
    """A Gaussian belief in the four parameters (SI).

    Attributes:
        mean: the believed values.
        cov: 4x4 covariance, order (E_R, E_T, K_theta, K_rho).
        source: ``priors`` or ``estimate``, for messages.
        rate_floor: the least K_theta (rad^2/m) and K_rho (m) a prediction
            assumes (the priors' values for a belief from an estimate).
        turns: a general-path fit's turn errors the estimate pins, as
            (name, value, standard deviation) in SI (``e_turn``... no unit,
            ``K_spin`` rad^2/rad; names as odohil/science/estimators/paths.py
            fits them), the deviation widened like the four's; empty: exact
            turns (the four-parameter model).
    """

    mean: ErrorParameters
    cov: FloatArray
    source: str = "priors"
    rate_floor: tuple[float, float] = (0.0, 0.0)
    turns: tuple[tuple[str, float, float], ...] = ()

    @classmethod
    def from_priors(cls, priors: ParameterPriors, *, turns_exact: bool = True) -> ParameterBelief:
        """The robot description's ``[priors]``; without them (``given`` False)
        :data:`UNKNOWN_ROBOT_PAPER`; unless ``turns_exact``, the turns of
        :data:`UNKNOWN_TURNS` (``[priors]`` say nothing of turns)."""
        turns = () if turns_exact else UNKNOWN_TURNS
        if priors.given:
            return cls(priors.mean, priors.cov(), "priors", turns=turns)
        mean = ErrorParameters.from_paper_units(*(m for m, _ in UNKNOWN_ROBOT_PAPER))
        sd = np.array(
            ErrorParameters.from_paper_units(*(s for _, s in UNKNOWN_ROBOT_PAPER)).as_tuple()
        )  # deviations scale as the values do
        return cls(mean, np.diag(sd**2), "priors", turns=turns)

    @classmethod
    def from_estimate(
        cls,
        values: Sequence[float],
        stderrs: Sequence[float | None],
        correlation: Sequence[Sequence[float | None]] | None,
        priors: ParameterPriors,
    ) -> ParameterBelief:
        """An estimate's values, standard errors (None or inf when unknown) and
        correlation, SI. Standard errors are widened by
        :data:`ESTIMATE_INFLATION`; a parameter the estimate does not pin (or
        pins less well than the priors) keeps its prior, except a variance rate
        whose estimate plus its widened standard error lies above the prior's
        mean plus one deviation: a robot far noisier than the priors (no
        ``[priors]``: the paper's Nomad) would otherwise be predicted with the
        priors' spread until the estimate's standard error beat the prior's, a
        relative error of K_theta 0.39 deg^2/m needing some 500 trials, and
        about one clean trial in ten would trip the slip check (issue 31).
        Negative variance rates are clipped to 0."""
        mean = list(float(v) for v in values)
        mean[2], mean[3] = max(mean[2], 0.0), max(mean[3], 0.0)
        sd = np.empty(4)
        corr = np.eye(4)
        use = np.zeros(4, dtype=bool)
        prior_mean = priors.mean.as_tuple()
        for a in range(4):
            s = stderrs[a]
            if (
                s is not None
                and math.isfinite(s)
                and (
                    ESTIMATE_INFLATION * s < priors.sd[a]
                    or (a >= 2 and mean[a] + ESTIMATE_INFLATION * s > prior_mean[a] + priors.sd[a])
                )
            ):  # a variance rate the data puts above the prior's reach is the data's
                sd[a] = ESTIMATE_INFLATION * float(s)
                use[a] = True
            else:
                sd[a] = priors.sd[a]
                mean[a] = prior_mean[a]
        if correlation is not None:
            for a in range(4):
                for b in range(4):
                    r = correlation[a][b]
                    if a != b and use[a] and use[b] and r is not None and math.isfinite(r):
                        corr[a, b] = float(r)
        cov = corr * np.outer(sd, sd)
        eig = np.linalg.eigvalsh(0.5 * (cov + cov.T))
        if eig.min() <= 0:
            cov = np.diag(sd**2)
        floor = (priors.mean.k_theta, priors.mean.k_rho)
        return cls(ErrorParameters(*mean), cov, "estimate", floor)

    @classmethod
    def from_result(
        cls, result: EstimateResult, priors: ParameterPriors, *, turns_exact: bool = True
    ) -> ParameterBelief:
        """An estimate's values, standard errors and correlation (see
        :meth:`from_estimate`), and a general-path fit's turn errors (e_turn...,
        K_spin) where it pins them (a finite standard error, widened by
        :data:`ESTIMATE_INFLATION`; their correlations with the four are left
        out; none when the estimate does not pin E_R, with which squares of
        one direction confound e_turn): a Create 2 square's prediction without them is off by 2 pi
        e_turn in heading and lacks its spins' spread, so nearly every clean
        square would trip the slip check and the prior would pull the choice
        of pose (tests/science/test_turn_belief.py). Unless ``turns_exact``,
        the turn errors it does not pin (an estimate of straight runs pins
        none; one split by direction pins one direction's; a K_spin no
        larger than its widened deviation, as two or three squares fit it, at
        0 with a deviation of 1e-5, which made e_turn look 5 times surer than
        it was and tripped the check on clean squares) are
        :data:`UNKNOWN_TURNS`' (listed first, so that a pinned class's e_turn
        overrides the unknown one: odohil/science/moments.py
        ``turn_errors_from``)."""
        belief = cls._four_and_turns(result, priors)
        if turns_exact:
            return belief
        fitted = tuple(
            t for t in belief.turns if t[0] != "K_spin" or t[1] > t[2]
        )  # a K_spin not above its widened deviation sits at its floor: not pinned
        pinned = {name for name, _, _ in fitted}
        unknown = tuple(t for t in UNKNOWN_TURNS if t[0] not in pinned)
        return replace(belief, turns=unknown + fitted)

    @classmethod
    def _four_and_turns(cls, result: EstimateResult, priors: ParameterPriors) -> ParameterBelief:
        """:meth:`from_result` of a robot whose turns are exact."""
        names = [p.name for p in result.parameters]
        rows = [names.index(name) for name in PARAMETER_NAMES]
        correlation = result.correlation
        belief = cls.from_estimate(
            [result.parameters[i].value for i in rows],
            [result.parameters[i].stderr for i in rows],
            None if correlation is None else [[correlation[i][j] for j in rows] for i in rows],
            priors,
        )
        e_r = result.parameters[rows[0]].stderr
        if e_r is None or not (math.isfinite(e_r) and ESTIMATE_INFLATION * e_r < priors.sd[0]):
            return belief  # E_R is the prior's: a turn scale fitted beside another E_R is not
        turns = tuple(
            (p.name, max(p.value, 0.0) if p.name == "K_spin" else p.value,
             ESTIMATE_INFLATION * p.stderr)
            for p in result.parameters
            if p.name not in PARAMETER_NAMES and p.stderr is not None and math.isfinite(p.stderr)
        )  # fmt: skip
        return replace(belief, turns=turns)


@dataclass(frozen=True, eq=False)
class SlipCheck:
    """Does the solved pose agree with the prediction and the distances?

    Attributes:
        statistic: T (see the module docstring), chi^2 with ``dof`` degrees of
            freedom for clean distances.
        dof: the number of distances.
        limit: the (1 - :data:`SLIP_LEVEL`) quantile.
        tripped: ``statistic > limit``.
        suspect: index of the most likely wrong distance.
        suspect_label: its name (e.g. ``d3 (screw C)``).
        shift_m: the error of the suspect distance that best explains T, metres
            (measured minus expected).
    """

    statistic: float
    dof: int
    limit: float
    tripped: bool
    suspect: int
    suspect_label: str
    shift_m: float

    def message(self) -> str:
        """Plain-language summary for the operator."""
        return (
            f"the trial does not fit the other trials and the encoders (T = "
            f"{self.statistic:.1f}, limit {self.limit:.1f} at level {SLIP_LEVEL:g}); the "
            f"most likely wrong distance is {self.suspect_label} (about "
            f"{self.shift_m * 1000:+.0f} mm off)"
        )


@dataclass(frozen=True, eq=False)
class PoseSelection:
    """The chosen pose of one trial and what the checks say.

    Attributes:
        solution: the floor-mark solution, chosen with the predictive prior.
        predicted: the predictive distribution used.
        ambiguous: a second candidate stays plausible.
        plausible: the plausible candidates (best first; one unless ambiguous).
        slip: the slip check of the chosen pose.
    """

    solution: MarkSolution
    predicted: PoseDistribution
    ambiguous: bool
    plausible: tuple[MarkCandidate, ...]
    slip: SlipCheck


def predictive_pose(
    design: Design | PathDesign,
    belief: ParameterBelief,
    encoder_end_pose: Sequence[float] | FloatArray | None = None,
) -> PosePrior:
    """The predictive distribution of one trial's pose change (dx m, dy m,
    dtheta rad) under ``belief``, shifted by the encoders' departure from the
    design's ideal end pose (see the module docstring)."""
    mean, cov = _moments(
        design, belief.mean.as_tuple(), _key(belief.cov), belief.rate_floor, belief.turns
    )
    mean = mean.copy()
    if encoder_end_pose is not None:
        ideal = np.array(design.path().encoder_end_pose())
        offset = np.asarray(encoder_end_pose, dtype=np.float64) - ideal
        offset[2] = wrap_angle(float(offset[2]))
        mean += offset
    return PosePrior(mean=mean, cov=cov)


def _key(cov: FloatArray) -> tuple[float, ...]:
    return tuple(float(v) for v in np.asarray(cov, dtype=np.float64).ravel())


@lru_cache(maxsize=256)
def _moments(
    design: Design | PathDesign,
    values: tuple[float, ...],
    cov_key: tuple[float, ...],
    floor: tuple[float, float],
    turns: tuple[tuple[str, float, float], ...] = (),
) -> tuple[FloatArray, FloatArray]:
    params = ErrorParameters(*values)
    cov_params = np.array(cov_key).reshape(4, 4)
    path = design.path()
    derivatives = moment_derivatives(path, params)
    sd = np.sqrt(np.clip(np.diag(cov_params), 0.0, None))
    widened = ErrorParameters(
        params.e_r,
        params.e_t,
        max(params.k_theta + sd[2], floor[0]),
        max(params.k_rho + sd[3], floor[1]),
    )
    # the widened rates give the model's spread; the mean's dependence on
    # the parameters adds their uncertainty
    model_cov = moment_derivatives(path, widened).cov
    cov = model_cov + derivatives.d_mean.T @ cov_params @ derivatives.d_mean
    mean = derivatives.mean.copy()
    if turns:
        names = [name for name, _, _ in turns]
        at = np.array([value for _, value, _ in turns])
        turn_sd = np.array([s for _, _, s in turns])
        raised = np.array(
            [v + s if name == "K_spin" else v for name, v, s in turns]
        )  # K_spin raised by its deviation, as K_theta and K_rho are
        mean = pose_moments(path, params, turn_errors_from(names, list(at))).mean
        cov = (
            cov - model_cov + pose_moments(path, widened, turn_errors_from(names, list(raised))).cov
        )
        for j, (name, value, s) in enumerate(turns):
            if name == "K_spin" or s == 0.0:
                continue  # a rate moves the spread, not the mean
            step = max(1e-7, 1e-4 * abs(value))
            high, low = at.copy(), at.copy()
            high[j] += step
            low[j] -= step
            d_mean = (
                pose_moments(path, params, turn_errors_from(names, list(high))).mean
                - pose_moments(path, params, turn_errors_from(names, list(low))).mean
            ) / (2.0 * step)
            cov = cov + np.outer(d_mean, d_mean) * turn_sd[j] ** 2
    return mean, 0.5 * (cov + cov.T)


def select_pose(
    description: RobotDescription,
    marks: MarkDistances,
    encoder_end_pose: Sequence[float] | FloatArray,
    predicted: PoseDistribution,
) -> PoseSelection:
    """Choose the pose of one trial and check it (see the module docstring).

    Raises:
        MeasurementError: malformed distances or poses.
        InconsistentMeasurementError: no rigid motion explains the distances.
    """
    solution = solve_marks(description, marks, encoder_end_pose, prior=predicted)
    best = solution.candidates[0]
    sd = np.sqrt(np.clip(np.diag(solution.cov), 0.0, None)) + 1e-12
    rivals = [
        c
        for c in solution.candidates[1:]
        if best.log_likelihood - c.log_likelihood < _LOG_AMBIGUOUS
        and np.isfinite(c.log_likelihood)
        and _separation(c.pose, best.pose, sd) > AMBIGUITY_SEPARATION
    ]
    plausible = (best, *rivals)
    slip = slip_check(description, marks, solution.pose_change, predicted)
    return PoseSelection(
        solution=solution,
        predicted=predicted,
        ambiguous=len(plausible) > 1,
        plausible=plausible,
        slip=slip,
    )


def unmeasured_pair(description: RobotDescription) -> tuple[str, str]:
    """A cross distance (start screw, end screw) the description does not list:
    the one to ask for when a trial is ambiguous (the first pair, in screw
    order, of screws as far apart as possible)."""
    listed = set(description.cross_pairs)
    points = description.positions()
    names = description.screw_names
    pairs = [
        (float(np.hypot(*(points[i] - points[j]))), names[i], names[j])
        for i in range(len(names))
        for j in range(len(names))
        if i != j and (names[i], names[j]) not in listed
    ]
    _, start, end = max(pairs, key=lambda p: p[0])
    return start, end


def resolve_with_extra(
    description: RobotDescription,
    marks: MarkDistances,
    selection: PoseSelection,
    extra: Sequence[tuple[str, str, float]],
) -> PoseSelection:
    """Re-score an ambiguous trial's plausible candidates with extra cross
    distances (start screw, end screw, metres) measured after the fact; the
    trial stays ambiguous unless one candidate is then at least
    :data:`CLEAR_CUT_LIKELIHOOD_RATIO` times as likely as every other."""
    if not extra:
        return selection
    pairs = tuple((start, end) for start, end, _ in extra)
    measured = np.array([value for _, _, value in extra])
    scored: list[tuple[float, MarkCandidate]] = []
    for candidate in selection.plausible:
        log_likelihood = candidate.log_likelihood
        for (start, end), value in zip(pairs, measured, strict=True):
            probe = replace(description, cross_pairs=((start, end),))
            expected = marks_from_pose(probe, candidate.pose).cross_m[0]
            log_likelihood -= 0.5 * ((value - expected) / description.sigma_m) ** 2
        scored.append((log_likelihood, candidate))
    scored.sort(key=lambda item: -item[0])
    best_ll, best = scored[0]
    rivals = tuple(c for ll, c in scored[1:] if best_ll - ll < _LOG_AMBIGUOUS)
    solution = selection.solution
    if best is not solution.candidates[0]:
        solution = replace(
            solution,
            pose_change=best.pose,
            cov=pose_covariance(description, best.pose),
            chi2=best.chi2,
        )
    solution = replace(
        solution,
        clear_cut=not rivals,
        reason="" if not rivals else solution.reason,
    )
    return replace(
        selection,
        solution=solution,
        ambiguous=bool(rivals),
        plausible=(best, *rivals),
        slip=slip_check(description, marks, best.pose, selection.predicted),
    )


def _separation(a: FloatArray, b: FloatArray, sd: FloatArray) -> float:
    delta = np.asarray(a, dtype=np.float64) - np.asarray(b, dtype=np.float64)
    delta[2] = wrap_angle(float(delta[2]))
    return float(np.max(np.abs(delta) / sd))


def slip_check(
    description: RobotDescription,
    marks: MarkDistances,
    pose_change: Sequence[float] | FloatArray,
    predicted: PoseDistribution,
) -> SlipCheck:
    """The slip check of a solved pose against the predictive distribution
    (see the module docstring)."""
    pose = np.asarray(pose_change, dtype=np.float64)
    distances, jac = linearised_marks(description, pose)
    measured = marks.as_array()
    delta = pose - np.asarray(predicted.mean, dtype=np.float64)
    delta[2] = wrap_angle(float(delta[2]))
    innovation = measured - distances + jac @ delta
    m = measured.size
    s = jac @ np.asarray(predicted.cov, dtype=np.float64) @ jac.T
    s += description.sigma_m**2 * np.eye(m)
    statistic, weighted, s_inv = _innovation_test(innovation, s)
    explained = weighted**2 / np.diag(s_inv)
    suspect = int(np.argmax(explained))
    limit = distributions.chi2_isf(SLIP_LEVEL, m)
    return SlipCheck(
        statistic=statistic,
        dof=m,
        limit=limit,
        tripped=statistic > limit,
        suspect=suspect,
        suspect_label=distance_labels(description)[suspect],
        shift_m=float(weighted[suspect] / s_inv[suspect, suspect]),
    )


def _innovation_test(
    innovation: FloatArray, cov: FloatArray
) -> tuple[float, FloatArray, FloatArray]:
    """T = v^T S^-1 v of an innovation v with covariance S; also S^-1 v and S^-1."""
    s_inv = np.asarray(np.linalg.inv(0.5 * (cov + cov.T)), dtype=np.float64)
    weighted = s_inv @ innovation
    return float(innovation @ weighted), weighted, s_inv


@dataclass(frozen=True, eq=False)
class ScaleCheck:
    """How far from its start the measurement and the encoders put the robot.

    Attributes:
        what: ``displacement`` (the end point) or ``excursion`` (the farthest
            point of the path).
        measured_m: the measurement's, m.
        encoders_m: the encoders', m.
        off: below 1/:data:`SCALE_RATIO` or above :data:`SCALE_RATIO` times
            the encoders' (see the module docstring).
    """

    what: str
    measured_m: float
    encoders_m: float
    off: bool

    @property
    def ratio(self) -> float:
        """measured / encoders (inf when the encoders say 0)."""
        return self.measured_m / self.encoders_m if self.encoders_m > 0 else math.inf


@dataclass(frozen=True, eq=False)
class PoseCheck:
    """A measured pose change against the prediction and the encoders.

    Attributes:
        statistic: T = v^T S^-1 v (see the module docstring), chi^2 with 3
            degrees of freedom when the measurement and the model are right.
        limit: its (1 - :data:`SLIP_LEVEL`) quantile.
        scales: the distance from the start, then the path's farthest point
            when the source saw it.
    """

    statistic: float
    limit: float
    scales: tuple[ScaleCheck, ...]

    @property
    def doubtful(self) -> bool:
        """T beyond its (1 - :data:`SLIP_LEVEL`) quantile."""
        return self.statistic > self.limit

    @property
    def implausible(self) -> bool:
        """T beyond :data:`IMPLAUSIBLE_SIGMAS` squared, or a distance off scale."""
        return self.statistic > IMPLAUSIBLE_SIGMAS**2 or any(s.off for s in self.scales)

    def to_json(self) -> dict[str, float]:
        """The numbers, for the journal."""
        data = {"T": self.statistic, "limit": self.limit}
        for scale in self.scales:
            data[f"{scale.what}_m"] = scale.measured_m
            data[f"encoder_{scale.what}_m"] = scale.encoders_m
        return data


def pose_statistic(
    pose_change: Sequence[float] | FloatArray,
    cov: Sequence[Sequence[float]] | FloatArray,
    predicted: PoseDistribution,
) -> float:
    """T = v^T (P + C)^-1 v of a measured pose change (covariance C) against
    the prediction (mean mu, covariance P), v = x - mu with theta wrapped."""
    delta = np.asarray(pose_change, dtype=np.float64) - np.asarray(predicted.mean, dtype=np.float64)
    delta[2] = wrap_angle(float(delta[2]))
    total = np.asarray(predicted.cov, dtype=np.float64) + np.asarray(cov, dtype=np.float64)
    return _innovation_test(delta, total)[0]


def pose_check(
    pose_change: Sequence[float] | FloatArray,
    cov: Sequence[Sequence[float]] | FloatArray,
    predicted: PoseDistribution,
    encoder_end_pose: Sequence[float] | FloatArray,
    excursion: tuple[float, float] | None = None,
) -> PoseCheck:
    """The pose check of a measured pose change (see the module docstring).

    Args:
        pose_change: the measured (dx m, dy m, dtheta rad).
        cov: its 3x3 covariance.
        predicted: the predictive distribution (:func:`predictive_pose`).
        encoder_end_pose: the encoders' end pose in the start frame.
        excursion: the farthest the measurement and the encoders saw the robot
            from its start during the motion (m, m), when the source saw the path.
    """
    pose = np.asarray(pose_change, dtype=np.float64)
    statistic = pose_statistic(pose, cov, predicted)
    total = np.asarray(predicted.cov, dtype=np.float64) + np.asarray(cov, dtype=np.float64)
    spread = math.sqrt(max(float(np.linalg.eigvalsh(total[:2, :2]).max()), 0.0))
    pairs = [("displacement", float(np.hypot(*pose[:2])), float(np.hypot(*encoder_end_pose[:2])))]
    if excursion is not None:
        pairs.append(("excursion", float(excursion[0]), float(excursion[1])))
    scales = tuple(
        ScaleCheck(
            what,
            measured,
            encoders,
            off=measured < encoders / SCALE_RATIO - SCALE_FLOOR_M
            or measured > encoders * SCALE_RATIO + SCALE_FLOOR_M + IMPLAUSIBLE_SIGMAS * spread,
        )
        for what, measured, encoders in pairs
    )
    return PoseCheck(statistic, distributions.chi2_isf(SLIP_LEVEL, 3), scales)


def required_cross_distances(design: Design) -> int:
    """How many cross distances a trial of ``design`` needs for its pose to be
    picked reliably (docs/measurements.md, "How many cross distances"):
    two for a one-way design (an odd number of legs, k = 1/2, 3/2, ...), one
    for a closed design."""
    return 2 if design.n_legs % 2 == 1 else 1


def redundancy_problems(description: RobotDescription, designs: Sequence[Design]) -> list[str]:
    """Why the description's cross distances cannot disambiguate some designs
    (empty when they can)."""
    have = len(description.cross_pairs)
    problems: list[str] = []
    for design in dict.fromkeys(designs):
        need = required_cross_distances(design)
        if have < need:
            kind = "a one-way design" if need == 2 else "a closed design"
            problems.append(
                f"design {design.label()} is {kind} and needs at least {need} cross "
                f"distance(s) in the robot description's measurement.cross, which lists "
                f"{have}"
            )
    return problems


def check_redundancy(description: RobotDescription, designs: Sequence[Design]) -> None:
    """Refuse, before anything moves, designs the description's cross
    distances cannot disambiguate.

    Raises:
        RobotDescriptionError: the reasons, one per design.
    """
    problems = redundancy_problems(description, designs)
    if problems:
        raise RobotDescriptionError(
            "the floor marks cannot pick this plan's poses reliably: "
            + "; ".join(problems)
            + " (see docs/measurements.md, 'How many cross distances')"
        )


__all__ = [
    "ESTIMATE_INFLATION",
    "IMPLAUSIBLE_SIGMAS",
    "SCALE_FLOOR_M",
    "SCALE_RATIO",
    "SLIP_LEVEL",
    "UNKNOWN_ROBOT_PAPER",
    "UNKNOWN_TURNS",
    "ParameterBelief",
    "PoseCheck",
    "PoseSelection",
    "ScaleCheck",
    "SlipCheck",
    "check_redundancy",
    "pose_check",
    "pose_statistic",
    "predictive_pose",
    "redundancy_problems",
    "required_cross_distances",
    "resolve_with_extra",
    "select_pose",
    "slip_check",
    "unmeasured_pair",
]
