"""Estimating from trials of general paths, with a differential drive's turn errors.

Each :class:`~odohil.science.path_trials.PathTrial` carries its own encoder
path; its pose change is modelled as N(mu_i, Sigma_i + C_i) with the exact
moments of :func:`odohil.science.moments.pose_moments` (turn errors included)
and its measurement covariance C_i. The fit is the same machinery as the
forth-and-back designs' (odohil/science/estimators/likelihood.py, joint.py,
intervals.py, robust.py): Cox-Reid adjusted maximum likelihood by Fisher
scoring, Student-t intervals with Satterthwaite degrees of freedom for the
mean parameters, profile-likelihood intervals for the variance rates, the
robust fit's outlier mixture, and the same model check and verdict. Only the
model differs: one moment key per trial (its index) and the parameter vector

    phi = (E_R rad/m, E_T, log K_theta, log K_rho, e_turn..., log K_spin)

**Turn errors** (``turns_exact=False``): a turn of encoder angle a in class c
really turns a (1 + e_c), and a spin (a turn in place) adds N(0, K_spin |a|);
arcs (the heading changes of a curve cut into short legs) carry no noise of
their own, their noise is K_theta's along the legs. Which e_turn are fitted:

- one per kind of turn the data hold (``e_turn`` when they hold only spins or
  only arcs; ``e_turn_spin`` and ``e_turn_arc`` when both: a differential
  drive's spins and arcs slip differently, -0.7 % and -1.2 % on the optiodom
  robot, issue 20);
- per direction as well (``e_turn_ccw``/``e_turn_cw``, or
  ``e_turn_spin_ccw``, ...) when ``split_directions=True``, or, with the
  default ``split_directions=None``, when the data ask for it: both directions
  are present and a likelihood-ratio test of the split model against the
  unsplit one rejects at the 1 % level (the note says so, with its p-value);
- K_spin (rad^2/rad) when the data hold spins. Without spins it is not
  identifiable: it is fixed at 0 and a note says so (no interval is made up).

With ``turns_exact=True`` every turn error is fixed at 0: the paper's
four-parameter model.

Public API (stable; the log readers and the misfit checks use it):

- :func:`estimate_paths` (trials -> :class:`~odohil.science.estimators.result.EstimateResult`);
  ``result.parameter("e_turn")`` etc., JSON ``parameters.e_turn`` and
  ``parameters.K_spin`` (SI: no unit and rad^2/rad; paper units via
  :func:`odohil.units.parameter_to_paper`: K_spin in deg^2/deg);
- :func:`predict` (trials, result -> each trial's predicted mean, model and
  total covariance and residual at the fitted parameters);
- :func:`turn_errors_of` (result -> :class:`~odohil.science.moments.TurnErrors`).
"""

from __future__ import annotations

import math
from collections.abc import Hashable, Iterable, Sequence
from dataclasses import dataclass, field, replace
from functools import lru_cache
from typing import Literal

import numpy as np

from odohil import units
from odohil.errors import MeasurementError
from odohil.science import distributions
from odohil.science.estimators.checks import Criteria, distance_check, sufficiency
from odohil.science.estimators.estimate import honest_estimates
from odohil.science.estimators.joint import JointFit, joint_estimate
from odohil.science.estimators.likelihood import (
    GroupStats,
    Layout,
    ModelPoint,
    evaluate,
)
from odohil.science.estimators.memo import ResultMemo
from odohil.science.estimators.misfit import MisfitCheck, labels_of, misfit_check
from odohil.science.estimators.observations import align_heading
from odohil.science.estimators.result import (
    EstimateResult,
    ParameterEstimate,
    TrialDiagnostic,
)
from odohil.science.estimators.robust import (
    EPSILON,
    INFLATION,
    OUTLIER_WEIGHT,
    RobustFit,
    mixture_terms,
    robust_em,
)
from odohil.science.estimators.scores import point_scores, sandwich_ratio
from odohil.science.estimators.verdict import few_trial_groups, judge
from odohil.science.moments import (
    PathSet,
    TurnErrors,
    batch_moments,
    pose_moments,
    turn_errors_from,
)
from odohil.science.parameters import PARAMETER_NAMES, ErrorParameters
from odohil.science.path_trials import PathTrial
from odohil.science.paths import TURN_CLASSES, EncoderPath, FloatArray

PATH_METHODS = ("robust", "joint")
IntervalRule = Literal["honest", "wald"]
"""The intervals :func:`estimate_paths` gives: the estimate's (profile
likelihood and Satterthwaite t) or a live belief's Wald intervals."""
SPLIT_LEVEL = 0.01
"""Level of the likelihood-ratio test that splits e_turn by direction."""
_RELATIVE_STEP = 1e-4
_SCALES = (1e-3, 1e-2, 1e-6, 1e-5, 1e-2)
"""Typical magnitudes (SI) of E_R, E_T, K_theta, K_rho and the turn errors
(e_turn; K_spin, the last, uses it too): finite-difference steps are
1e-4 of max(|value|, this)."""
_K_START_FLOOR = 1e-12


@dataclass(frozen=True)
class TurnModel:
    """Which turn errors are fitted.

    Attributes:
        classes: per fitted e_turn, its name and the turn classes it covers
            (indices into odohil/science/paths.py TURN_CLASSES).
        k_spin: whether K_spin is fitted (the data hold spins).
    """

    classes: tuple[tuple[str, tuple[int, ...]], ...] = ()
    k_spin: bool = False

    @property
    def layout(self) -> Layout:
        """phi = (E_R, E_T, log K_theta, log K_rho, e_turn..., log K_spin)."""
        return _layout(self.classes, self.k_spin)

    def turn_errors(self, phi: FloatArray) -> TurnErrors | None:
        """The turn errors at phi (None when none are fitted)."""
        if not self.classes and not self.k_spin:
            return None
        scales = np.zeros(4)
        for i, (_, members) in enumerate(self.classes):
            scales[list(members)] = phi[4 + i]
        k_spin = math.exp(float(phi[-1])) if self.k_spin else 0.0
        return TurnErrors.of(scales, k_spin)


@lru_cache(maxsize=64)
def _layout(classes: tuple[tuple[str, tuple[int, ...]], ...], k_spin: bool) -> Layout:
    """:attr:`TurnModel.layout` (built once per turn model: the fit asks for
    it at every step)."""
    m = len(classes)
    names = (*PARAMETER_NAMES, *(name for name, _ in classes))
    rates: tuple[int, ...] = (2, 3)
    if k_spin:
        names = (*names, "K_spin")
        rates = (2, 3, 4 + m)
    floors = ((1, -0.99), *((4 + i, -0.99) for i in range(m)))
    return Layout(names, rates, (0, 1, *range(4, 4 + m)), floors)


def _turned(paths: Sequence[EncoderPath]) -> FloatArray:
    """(4,) per turn class, the |angle| turned over all the paths, rad."""
    turned = np.zeros(4)
    for path in paths:
        turned += path.turns.total_abs_rad
    return turned


def turn_model(paths: Sequence[EncoderPath], *, split_directions: bool) -> TurnModel:
    """The turn errors the paths can identify (module docstring)."""
    turned = _turned(paths)
    present = turned > 0
    kinds = [k for k, rows in (("spin", (0, 1)), ("arc", (2, 3))) if present[list(rows)].any()]
    classes: list[tuple[str, tuple[int, ...]]] = []
    for kind in kinds:
        rows = (0, 1) if kind == "spin" else (2, 3)
        prefix = "e_turn" if len(kinds) == 1 else f"e_turn_{kind}"
        if split_directions:
            for row in rows:
                if present[row]:
                    direction = TURN_CLASSES[row].split()[1]
                    classes.append((f"{prefix}_{direction}", (row,)))
        else:
            classes.append((prefix, rows))
    return TurnModel(tuple(classes), k_spin=bool(turned[0] + turned[1] > 0))


def _directions_present(paths: Sequence[EncoderPath]) -> bool:
    turned = _turned(paths)
    return bool((turned[0] > 0 and turned[1] > 0) or (turned[2] > 0 and turned[3] > 0))


@dataclass(frozen=True)
class PathModel:
    """The moments of each trial's path (key: its index) at any phi
    (a :class:`~odohil.science.estimators.likelihood.MomentModel`), all
    trials at once (:func:`odohil.science.moments.batch_moments`)."""

    paths: PathSet
    turns: TurnModel

    @property
    def layout(self) -> Layout:
        """See :attr:`TurnModel.layout`."""
        return self.turns.layout

    def rows(self, phis: FloatArray) -> FloatArray:
        """(Q, 9) batch rows (odohil/science/moments.py BATCH_COLUMNS) of phis (Q, p)."""
        phis = np.atleast_2d(phis)
        out = np.zeros((phis.shape[0], 9))
        out[:, :2] = phis[:, :2]
        out[:, 2:4] = np.exp(phis[:, 2:4])
        for i, (_, members) in enumerate(self.turns.classes):
            out[:, [4 + m for m in members]] = phis[:, 4 + i, None]
        if self.turns.k_spin:
            out[:, 8] = np.exp(phis[:, -1])
        return out

    def _columns(self) -> list[list[int]]:
        """Per parameter of the layout, the batch columns it sets."""
        out = [[0], [1], [2], [3]]
        out += [[4 + m for m in members] for _, members in self.turns.classes]
        if self.turns.k_spin:
            out.append([8])
        return out

    def moments(self, phis: FloatArray, keys: Sequence[Hashable]) -> tuple[FloatArray, FloatArray]:
        """The moments of ``keys`` (trial indices) at every row of ``phis``, a
        batch per row: with turn errors, a batch's (Q, 4) x (4, T) products
        round differently from one row's, and :meth:`point` does one row."""
        indices = [int(k) for k in keys if isinstance(k, int)]
        each = [batch_moments(self.paths, self.rows(phi)) for phi in np.asarray(phis, np.float64)]
        means = np.concatenate([m for m, _ in each])
        covs = np.concatenate([c for _, c in each])
        return means[:, indices], covs[:, indices]

    def point(self, phi: FloatArray, keys: Iterable[Hashable], derivatives: bool) -> ModelPoint:
        """The moments of ``keys`` (trial indices) at phi. Derivatives by
        finite differences in SI (as odohil/science/fisher.py: central,
        steps 1e-4 of max(|value|, a typical magnitude); one-sided second
        order for a variance rate within a step of 0), times d(SI)/d(phi)."""
        here = np.array(phi, dtype=np.float64)
        indices = [int(k) for k in keys if isinstance(k, int)]
        base = self.rows(here)[0]
        rows = [base]
        plan: list[tuple[float, bool]] = []
        if derivatives:
            si = self.layout.to_si(here)
            for a, columns in enumerate(self._columns()):
                step = _RELATIVE_STEP * max(abs(float(si[a])), _SCALES[min(a, 4)])
                one_sided = a in self.layout.log_rates and float(si[a]) - step < 0.0
                for offset in (1.0, 2.0) if one_sided else (1.0, -1.0):
                    row = base.copy()
                    row[columns] += offset * step
                    rows.append(row)
                plan.append((step, one_sided))
        means_all, covs_all = batch_moments(self.paths, np.array(rows))
        means: dict[Hashable, FloatArray] = {i: means_all[0, i] for i in indices}
        covs: dict[Hashable, FloatArray] = {i: covs_all[0, i] for i in indices}
        if not derivatives:
            return ModelPoint(here, means, covs, None, None, here, self)
        jac = np.diag(self.layout.jacobian(here))
        d_mean = np.empty((len(plan), *means_all.shape[1:]))
        d_cov = np.empty((len(plan), *covs_all.shape[1:]))
        for a, (step, one_sided) in enumerate(plan):
            first, second = 1 + 2 * a, 2 + 2 * a
            if one_sided:
                d_mean[a] = -1.5 * means_all[0] + 2 * means_all[first] - 0.5 * means_all[second]
                d_cov[a] = -1.5 * covs_all[0] + 2 * covs_all[first] - 0.5 * covs_all[second]
            else:
                d_mean[a] = 0.5 * (means_all[first] - means_all[second])
                d_cov[a] = 0.5 * (covs_all[first] - covs_all[second])
            d_mean[a] *= jac[a] / step
            d_cov[a] *= jac[a] / step
        d_means: dict[Hashable, FloatArray] = {i: d_mean[:, i] for i in indices}
        d_covs: dict[Hashable, FloatArray] = {i: d_cov[:, i] for i in indices}
        return ModelPoint(here, means, covs, d_means, d_covs, here, self)


@dataclass(frozen=True)
class _TrialGroup:
    """One trial as a likelihood group (n = 1, weighted residual)."""

    key: int
    reference: float
    weight: float
    total: FloatArray
    outer: FloatArray
    measurement_cov: FloatArray
    n: int = 1


def _groups(trials: Sequence[PathTrial], weights: FloatArray) -> list[GroupStats]:
    out: list[GroupStats] = []
    for i, (trial, w) in enumerate(zip(trials, weights, strict=True)):
        v = trial.pose_change
        out.append(
            _TrialGroup(i, float(v[2]), float(w), w * v, w * np.outer(v, v), trial.measurement_cov)
        )
    return out


def path_groups(trials: Sequence[PathTrial], weights: FloatArray | None = None) -> list[GroupStats]:
    """The trials as likelihood groups (one each, keyed by its index), with
    ``weights`` (1 each when None): what the fit and its intervals use."""
    return _groups(trials, np.ones(len(trials)) if weights is None else weights)


def _distances(trials: Sequence[PathTrial], point: ModelPoint) -> tuple[FloatArray, FloatArray]:
    """(squared Mahalanobis distance, log det of the total covariance) per trial."""
    d2 = np.empty(len(trials))
    log_det = np.empty(len(trials))
    for i, trial in enumerate(trials):
        mean = align_heading(point.means[i], float(trial.pose_change[2]))
        cov = point.covs[i] + trial.measurement_cov
        cov = 0.5 * (cov + cov.T)
        resid = trial.pose_change - mean
        sign, log_det[i] = np.linalg.slogdet(cov)
        if sign <= 0:
            d2[i], log_det[i] = math.inf, math.inf
            continue
        d2[i] = float(resid @ np.linalg.solve(cov, resid))
    return d2, log_det


@dataclass(frozen=True)
class _RobustPaths:
    """The trials as :class:`~odohil.science.estimators.robust.RobustTrials`."""

    trials: Sequence[PathTrial]

    def __len__(self) -> int:
        return len(self.trials)

    def distances(self, fit: JointFit) -> FloatArray:
        return _distances(self.trials, fit.point)[0]

    def groups(self, weights: FloatArray) -> Sequence[GroupStats]:
        return _groups(self.trials, weights)

    def scores(self, fit: JointFit, weights: FloatArray) -> tuple[FloatArray, FloatArray]:
        point = fit.point
        if point.d_means is None or not np.array_equal(point.anchor, point.phi):
            point = point.moved(point.phi, derivatives=True)
        return point_scores(point, _rows(self.trials), weights)

    def mixture_nll(self, fit: JointFit) -> float:
        d2, log_det = _distances(self.trials, fit.point)
        return mixture_terms(d2, log_det)


def _rows(trials: Sequence[PathTrial]) -> list[tuple[Hashable, FloatArray, FloatArray]]:
    return [(i, t.pose_change, t.measurement_cov) for i, t in enumerate(trials)]


def start_point(trials: Sequence[PathTrial], turns: TurnModel) -> FloatArray:
    """A start for the likelihood from the heading changes alone: E[Delta] is
    linear in E_R and the e_turn (least squares), Var Delta is K_theta rho +
    K_spin S + the measurement variance (least squares on the squared
    residuals, rates kept positive); E_T 0 and K_rho from the spread of the
    end points along the path."""
    layout = turns.layout
    n = len(trials)
    design = np.zeros((n, 1 + len(turns.classes)))
    delta = np.empty(n)
    for i, trial in enumerate(trials):
        path = trial.path
        design[i, 0] = path.signed_distance_m
        for j, (_, members) in enumerate(turns.classes):
            design[i, 1 + j] = path.turns.total_rad[list(members)].sum()
        encoder = path.net_turn_rad - path.winding_rad
        delta[i] = units.angle_near(float(trial.pose_change[2]), encoder) - encoder
    coef = np.linalg.lstsq(design, delta, rcond=None)[0]
    resid2 = (delta - design @ coef) ** 2 - np.array([t.measurement_cov[2, 2] for t in trials])
    rho = np.array([t.path.distance_m for t in trials])
    spun = np.array([t.path.turns.spin_total_rad for t in trials])
    columns = [rho, spun] if turns.k_spin else [rho]
    rates = np.linalg.lstsq(np.stack(columns, axis=1), resid2, rcond=None)[0]
    rates = np.maximum(rates, 0.0)
    phi = np.zeros(layout.size)
    phi[0] = coef[0]
    k_theta = max(float(rates[0]), float(np.mean(np.maximum(resid2, 0.0)) / rho.mean()) * 0.1)
    phi[2] = math.log(max(k_theta, _K_START_FLOOR))
    spread = [
        float(np.sum((t.pose_change[:2] - np.array(t.path.encoder_end_pose()[:2])) ** 2))
        for t in trials
    ]
    phi[3] = math.log(max(0.01 * float(np.mean(spread)) / float(rho.mean()), _K_START_FLOOR))
    phi[4 : 4 + len(turns.classes)] = coef[1:]
    if turns.k_spin:
        phi[-1] = math.log(max(float(rates[1]), 1e-3 * k_theta, _K_START_FLOOR))
    return phi


def _fit(trials: Sequence[PathTrial], turns: TurnModel) -> tuple[PathModel, JointFit]:
    model = PathModel(PathSet.of(tuple(t.path for t in trials)), turns)
    groups = _groups(trials, np.ones(len(trials)))
    fit = joint_estimate(groups, start_point(trials, turns), cox_reid=True, model=model)
    return model, fit


def fit_paths(
    trials: Sequence[PathTrial], *, turns_exact: bool, split_directions: bool = False
) -> JointFit:
    """The Gaussian (Cox-Reid adjusted) maximum-likelihood fit alone: point
    estimate and expected information, no intervals or checks (the fast part
    of :func:`estimate_paths`; ``fit.values`` in the order of
    ``fit.point.layout.names``)."""
    turns = (
        TurnModel()
        if turns_exact
        else turn_model([t.path for t in trials], split_directions=split_directions)
    )
    return _fit(trials, turns)[1]


def _plain_nll(trials: Sequence[PathTrial], fit: JointFit) -> float:
    return evaluate(_groups(trials, np.ones(len(trials))), fit.point).nll


def _label(trial: PathTrial) -> str:
    text = f"{trial.family} {trial.direction}"
    return f"{text}, {trial.source}" if trial.source else text


@dataclass(frozen=True)
class TrialPrediction:
    """One trial's prediction at the fitted parameters.

    Attributes:
        mean: (3,) predicted (x m, y m, Delta rad), Delta within pi of the
            measured one.
        model_cov: (3, 3) the model's covariance of the pose change.
        cov: (3, 3) model plus measurement covariance (what the residual has).
        residual: (3,) measured minus predicted (m, m, rad).
    """

    mean: FloatArray
    model_cov: FloatArray
    cov: FloatArray
    residual: FloatArray = field(default_factory=lambda: np.zeros(3))


def turn_errors_of(result: EstimateResult) -> TurnErrors:
    """The turn errors of a fit (zero where it fitted none, e.g. a
    four-parameter fit), from its parameters' names (module docstring)."""
    return turn_errors_from(
        [e.name for e in result.parameters], [e.value for e in result.parameters]
    )


def predict(trials: Sequence[PathTrial], result: EstimateResult) -> list[TrialPrediction]:
    """Each trial's predicted mean and covariance, and its residual, at the
    parameters of ``result`` (any estimate: its turn errors where it has them)."""
    turns = turn_errors_of(result)
    out = []
    for trial in trials:
        m = pose_moments(trial.path, result.params, None if turns.exact else turns)
        mean = align_heading(m.mean, float(trial.pose_change[2]))
        cov = m.cov + trial.measurement_cov
        out.append(TrialPrediction(mean, m.cov, 0.5 * (cov + cov.T), trial.pose_change - mean))
    return out


def _number(trials: Sequence[PathTrial]) -> list[PathTrial]:
    return [t if t.trial is not None else replace(t, trial=i + 1) for i, t in enumerate(trials)]


_PATH_MEMO: ResultMemo[EstimateResult] = ResultMemo(16)
"""The last estimates of :func:`estimate_paths` (odohil/science/estimators/memo.py)."""


def _trial_key(trial: PathTrial) -> Hashable:
    """Everything of one trial an estimate reads (arrays by their bytes)."""
    pose, cov = trial.pose_change, trial.measurement_cov
    return (
        trial.path, pose.shape, pose.tobytes(), cov.shape, cov.tobytes(), trial.source,
        trial.span_s, trial.trial, trial.family, trial.direction,
    )  # fmt: skip


def estimate_paths(
    trials: Sequence[PathTrial],
    *,
    turns_exact: bool,
    method: str = "robust",
    split_directions: bool | None = None,
    exclude: Iterable[int] = (),
    criteria: Criteria | None = None,
    intervals: IntervalRule = "honest",
) -> EstimateResult:
    """Estimate the four parameters (and, unless ``turns_exact``, the turn
    errors) from trials of general paths (module docstring).

    Args:
        trials: the trials, each with its own encoder path.
        turns_exact: True: the four-parameter model (turn errors fixed at 0);
            False: e_turn per kind of turn (and K_spin with spins) fitted too.
        method: ``robust`` (default: outlier mixture, Cox-Reid adjusted) or
            ``joint`` (Gaussian maximum likelihood, Cox-Reid adjusted).
        split_directions: e_turn per direction (True), not (False), or as the
            data ask (None: likelihood-ratio test at 1 %).
        exclude: trial numbers to leave out.
        criteria: precision targets of the sufficiency check (four parameters).
        intervals: ``honest`` (profile likelihood for the variance rates,
            Satterthwaite t for the others: the estimate's intervals) or
            ``wald`` (value +- 1.96 standard errors, symmetric in log K: a
            live belief's, which reads values, standard errors and
            correlations only; the fit, standard errors and correlations are
            the same either way, and the profile intervals cost about half
            of the whole estimate).

    The same trials with the same arguments are estimated once per process:
    the last 16 results are kept by everything they read (:data:`_PATH_MEMO`).

    Raises:
        MeasurementError: an unknown method, an excluded number that is no
            trial's, or fewer trials than parameters.
    """
    wanted = tuple(sorted(set(int(t) for t in exclude)))
    key = (tuple(map(_trial_key, trials)), turns_exact, method, split_directions, wanted,
           criteria, intervals)  # fmt: skip
    return _PATH_MEMO.get(
        key,
        lambda: _estimate_paths(
            trials, turns_exact, method, split_directions, wanted, criteria, intervals
        ),
    )


def _estimate_paths(
    trials: Sequence[PathTrial],
    turns_exact: bool,
    method: str,
    split_directions: bool | None,
    exclude: Iterable[int],
    criteria: Criteria | None,
    intervals: IntervalRule,
) -> EstimateResult:
    if method not in PATH_METHODS:
        raise MeasurementError(f"method must be one of {PATH_METHODS}, got {method!r}")
    numbered = _number(trials)
    wanted = sorted(set(int(t) for t in exclude))
    numbers = [int(t.trial or 0) for t in numbered]
    missing = [t for t in wanted if t not in numbers]
    if missing:
        span = f"{min(numbers)}..{max(numbers)}" if numbers else "none"
        raise MeasurementError(
            f"no trial numbered {', '.join(str(t) for t in missing)} to exclude "
            f"(the trials are numbered {span})"
        )
    kept = [t for t in numbered if t.trial not in wanted]
    paths = [t.path for t in kept]
    notes: list[str] = []
    if turns_exact:
        turns = TurnModel()
        notes.append("turns declared exact: e_turn and K_spin fixed at 0 (four-parameter model)")
    else:
        split = bool(split_directions)
        turns = turn_model(paths, split_directions=split)
    if len(kept) <= turns.layout.size:
        raise MeasurementError(
            f"{units.plural(len(kept), 'trial')} for {turns.layout.size} parameters: "
            f"need at least {turns.layout.size + 1}"
        )
    model, ml = _fit(kept, turns)
    if not turns_exact and split_directions is None and _directions_present(paths):
        split_turns = turn_model(paths, split_directions=True)
        if split_turns.layout.size > turns.layout.size and len(kept) > split_turns.layout.size:
            split_model, split_ml = _fit(kept, split_turns)
            statistic = 2.0 * (_plain_nll(kept, ml) - _plain_nll(kept, split_ml))
            extra = split_turns.layout.size - turns.layout.size
            p_value = distributions.chi2_sf(statistic, extra)
            if p_value < SPLIT_LEVEL:
                turns, model, ml = split_turns, split_model, split_ml
                notes.append(
                    f"e_turn split by direction: the directions' turn scales differ "
                    f"(likelihood-ratio p = {p_value:.2g})"
                )
            else:
                notes.append(
                    f"one e_turn for both directions (likelihood-ratio test of a split: "
                    f"p = {p_value:.2g})"
                )
    if not turns_exact and not turns.k_spin:
        notes.append("K_spin fixed at 0: no spins in the data, so it is not identifiable")
    if not turns_exact and not turns.classes:
        notes.append("no turns in the data: e_turn not identifiable, fixed at 0")
    return _result(kept, wanted, model, ml, method, notes, criteria, intervals)


def _result(
    trials: Sequence[PathTrial],
    excluded: Sequence[int],
    model: PathModel,
    ml: JointFit,
    method: str,
    notes: list[str],
    criteria: Criteria | None,
    intervals: IntervalRule = "honest",
) -> EstimateResult:
    layout = model.layout
    state = f"converged in {ml.iterations} steps" if ml.converged else "DID NOT CONVERGE"
    rob: RobustFit | None = None
    if method == "robust":
        rob = robust_em(_RobustPaths(trials), ml)
        fit = rob.fit
        weights = rob.clean_probability + (1.0 - rob.clean_probability) / INFLATION
        ratio = sandwich_ratio(rob.scores, rob.information)
        named = [int(i) for i in np.flatnonzero(rob.clean_probability < OUTLIER_WEIGHT)]
        converged = rob.converged and ml.converged
        notes.insert(
            0,
            f"robust maximum likelihood (outlier probability {EPSILON:g} per trial, "
            f"Cox-Reid adjusted), general paths: {rob.em_iterations} EM steps from the "
            f"Gaussian fit ({state})",
        )
    else:
        fit = ml
        weights = np.ones(len(trials))
        scores, information = _RobustPaths(trials).scores(fit, weights)
        ratio = sandwich_ratio(scores, information)
        named = []
        converged = ml.converged
        notes.insert(0, f"joint maximum likelihood (Cox-Reid adjusted), general paths: {state}")
    if intervals == "wald":
        estimates = _wald_estimates(fit)
    else:
        estimates = honest_estimates(_groups(trials, weights), fit, ratio)
    cov = np.array(fit.covariance, dtype=np.float64)
    stderr = np.array([e.stderr for e in estimates])
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov / np.outer(stderr, stderr)
    corr[~np.isfinite(corr)] = math.nan
    np.fill_diagonal(corr, 1.0)
    d2, _ = _distances(trials, fit.point)
    check = distance_check(
        d2, [(None, t.trial, _label(t)) for t in trials], named, n_params=layout.size
    )
    misfit = _misfit(trials, model, fit, named, turns_exact=not model.turns.classes)
    verdict = judge(
        [],
        converged,
        [e.stderr if math.isfinite(e.ci95[1]) else math.inf for e in estimates],
        layout.names,
        check.fits,
        [o.label() for o in check.outliers],
        check.verdict,
        misfit=misfit,
        few=few_trial_groups([f"{t.family} {t.direction}" for t in trials]),
        group="a path family and direction",
    )
    gaussian: tuple[ParameterEstimate, ...] = ()
    diagnostics: tuple[TrialDiagnostic, ...] = ()
    if rob is not None:
        ml_values = ml.values
        ml_se = np.sqrt(np.clip(np.diag(ml.covariance), 0.0, None))
        gaussian = tuple(
            ParameterEstimate.build(name, float(v), float(se))
            for name, v, se in zip(layout.names, ml_values, ml_se, strict=True)
        )
        diagnostics = tuple(
            TrialDiagnostic(
                int(t.trial or i + 1),
                _label(t),
                float(rob.clean_probability[i]),
                tuple(float(v) for v in rob.influence[i]),
                layout.names,
            )
            for i, t in enumerate(trials)
        )
    params: ErrorParameters = fit.params
    return EstimateResult(
        method=method,
        n_trials=len(trials),
        params=params,
        parameters=estimates,
        covariance=tuple(tuple(float(v) for v in row) for row in cov),
        correlation=tuple(tuple(float(v) for v in row) for row in corr),
        model_check=check,
        sufficiency=sufficiency(estimates, params, [], criteria),
        notes=tuple(notes),
        verdict=verdict,
        converged=converged,
        gaussian=gaussian,
        trials=diagnostics,
        excluded=tuple(excluded),
        misfit=misfit,
    )


def _wald_estimates(fit: JointFit) -> tuple[ParameterEstimate, ...]:
    """Every parameter of the fit with its standard error (as
    ``honest_estimates`` gives it) and the Wald interval."""
    cov = np.array(fit.covariance, dtype=np.float64)
    diag = np.diag(cov)
    stderr = np.sqrt(np.where(np.isfinite(diag), np.clip(diag, 0.0, None), np.inf))
    return tuple(
        ParameterEstimate.build(name, float(value), float(se))
        for name, value, se in zip(fit.point.layout.names, fit.values, stderr, strict=True)
    )


TURN_HINT = "calibrate with turns_exact = false"
"""The misfit checks' advice on a bias of trials that turn, for a fit whose
turns were declared exact."""


def _misfit(
    trials: Sequence[PathTrial],
    model: PathModel,
    fit: JointFit,
    named: Sequence[int],
    *,
    turns_exact: bool,
) -> MisfitCheck:
    """The misfit checks (odohil/science/estimators/misfit.py) of the trials
    the fit kept (the robust fit's named outliers left out), at the fitted
    parameters, with the mean's derivatives in every fitted parameter (SI) and
    the fit's covariance; a parameter whose variance is not finite (a rate on
    its floor) is left out of the fitted projection (which only makes the
    check more cautious)."""
    keep = [i for i in range(len(trials)) if i not in set(named)]
    point = model.point(fit.point.phi, keep, derivatives=True)
    if point.d_means is None:
        raise AssertionError("the model point was asked for its derivatives")
    to_si = np.diag(model.layout.jacobian(fit.point.phi))
    with np.errstate(divide="ignore", invalid="ignore"):
        scale = np.where(to_si > 0, 1.0 / to_si, 0.0)
    residuals = np.empty((len(keep), 3))
    covs = np.empty((len(keep), 3, 3))
    jacobians = np.empty((len(keep), 3, model.layout.size))
    for row, i in enumerate(keep):
        trial = trials[i]
        mean = align_heading(point.means[i], float(trial.pose_change[2]))
        residuals[row] = trial.pose_change - mean
        covs[row] = point.covs[i] + trial.measurement_cov
        jacobians[row] = (point.d_means[i] * scale[:, None]).T
    cov = np.array(fit.covariance, dtype=np.float64)
    bad = ~np.isfinite(np.diag(cov))
    cov[bad, :] = 0.0
    cov[:, bad] = 0.0
    cov[~np.isfinite(cov)] = 0.0
    jacobians[~np.isfinite(jacobians)] = 0.0
    return misfit_check(
        residuals,
        covs,
        labels_of([trials[i] for i in keep]),
        jacobians,
        cov,
        fitted=True,
        turn_hint=TURN_HINT if turns_exact else "",
    )
