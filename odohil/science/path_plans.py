"""Plans of general paths: their Fisher information with a differential
drive's turn errors, and what a plan can and cannot estimate.

A plan is a list of (shape, number of trials), a shape a forth-and-back
:class:`~odohil.science.paths.Design`, an :class:`~odohil.science.paths.EncoderPath`,
or any :class:`~odohil.science.paths.Drivable` (a
:class:`~odohil.science.path_designs.PathDesign`: square, polygon, circle).
One trial of a shape is its encoder path driven once.

**Parameters** (SI). The four (E_R rad/m, E_T, K_theta rad^2/m, K_rho m); for
a robot whose turns carry error (``[robot] turns_exact = false``) also its turn
errors (odohil/science/moments.py :class:`~odohil.science.moments.TurnErrors`,
the model odohil/science/estimators/paths.py fits): a turn-scale error per
kind of turn, ``e_turn_spin`` (turns in place) and ``e_turn_arc`` (the
heading changes of a curve), or per kind and direction with
``split_directions`` (``e_turn_spin_ccw``, ``e_turn_spin_cw``,
``e_turn_arc_ccw``, ``e_turn_arc_cw``), and ``K_spin`` (rad^2/rad, the
spins' heading variance per radian). A robot whose turns are exact has the
four only.

**Measurement model**: the planner's (odohil/science/planner.py): each trial's
pose change is N(mu(theta), Sigma(theta) + C) with the exact moments of
:func:`odohil.science.moments.batch_moments` (turn errors included) and C the
floor-mark covariance averaged over the model's spread of pose changes
(:func:`odohil.science.fisher.pose_spread_measurement`'s rule, the same 512
standard normals), or one fixed C (motion capture), or none (exact poses).
The information of one trial is :func:`odohil.science.fisher.trial_information`'s
(mean and covariance parts) with derivatives by central differences in SI
(steps 1e-4 of max(|value|, a typical magnitude); one-sided second order for
a variance rate within a step of 0), as odohil/science/fisher.py.

**Estimable.** A turn error does not act on trials that have no turn of its
kind (no spins: K_spin; no clockwise spins: ``e_turn_spin_cw``...): it is not
estimable and not needed for those trials. Among the parameters that act,
one with no information (:data:`NO_INFORMATION`) is not estimable; the others are identified when
their unit vector lies in the range of the information in correlation form
(eigenvalues below :data:`SINGULAR` count as zero); otherwise a parameter is
confounded with those sharing its null direction, and only a combination of
them is identified. An identified parameter's Cramer-Rao standard error is
sqrt((I^+)_aa); a correlation above :data:`CONFOUNDED` with another is named
(identified, but only through small differences between the trials).
tests/estimation/test_path_plans.py holds these standard errors to the spread
of maximum-likelihood estimates over data sets simulated with the discrete
model (odohil/science/diff_drive.py :func:`~odohil.science.diff_drive.simulate_turn_errors`).

**Beside this module.** odohil/science/path_plan_search.py finds the best
plan in an operator time (:func:`~odohil.science.path_plan_search.best_plan`);
odohil/science/path_comparison.py says what general shapes buy over the best
forth-and-back plans of the same time; odohil/science/path_estimability.py is
the pre-flight's statement of what a plan can and cannot estimate.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from odohil import units
from odohil.errors import ParameterError
from odohil.science.fisher import (
    DEFAULT_POSE_SAMPLES,
    PARAMETER_SCALES,
    MomentDerivatives,
    measurement_covariance,
    trial_information,
)
from odohil.science.moments import BATCH_COLUMNS, PathSet, TurnErrors, batch_moments
from odohil.science.parameters import PARAMETER_NAMES, ErrorParameters
from odohil.science.paths import TURN_CLASSES, Drivable, EncoderPath, FloatArray, Turn
from odohil.science.planner import OperatorTime
from odohil.science.robot_description import RobotDescription

Shape = EncoderPath | Drivable
"""What one plan item drives: an encoder path, or a design giving one (a
forth-and-back :class:`~odohil.science.paths.Design`, a
:class:`~odohil.science.path_designs.PathDesign`)."""

DEFAULT_TURN_PRIOR = TurnErrors.uniform(0.01, k_spin=1e-4)
"""Turn errors at which the information is evaluated when none are known:
e_turn 1 % (the fake Create 2's 1.2 %, the optiodom robot's -0.7 % on spins
and -1.2 % on arcs, issue 20) and K_spin 1e-4 rad^2/rad (0.0057 deg^2/deg;
the fake Create 2's is 2e-4, the optiodom squares' about 1e-5). The mean
parameters' information hardly depends on them; K_spin's own does."""
TURN_SCALES = {"e_turn": 1e-2, "K_spin": 1e-5}
"""Typical magnitudes (SI) of the turn errors, beside
odohil/science/fisher.py PARAMETER_SCALES for the four."""
SINGULAR = 1e-8
"""Eigenvalues of the information in correlation form (each parameter's
diagonal scaled to 1) below this count as zero: a direction the trials do
not identify. Two parameters with correlation r give 1 - |r|; the finite
differences move these eigenvalues by about 1e-9."""
NO_INFORMATION = 1e-12
"""A parameter whose information (scaled by typical magnitudes) is below this
fraction of the largest parameter's has none."""
_NULL_LEAN = 1e-3
"""A parameter whose unit vector has more than this in the null space is not identified."""
_NULL_MEMBER = 0.05
"""A parameter with more than this in a null direction shares it."""
CONFOUNDED = 0.99
"""A correlation of two estimates above this (in absolute value) is named."""
_RELATIVE_STEP = 1e-4
_KIND_WORDS = {
    "spin ccw": "counter-clockwise spins",
    "spin cw": "clockwise spins",
    "arc ccw": "counter-clockwise arcs",
    "arc cw": "clockwise arcs",
}


def shape_path(shape: Shape) -> EncoderPath:
    """The encoder path of one trial of ``shape``."""
    return shape if isinstance(shape, EncoderPath) else shape.path()


def shape_label(shape: Shape) -> str:
    """A short name of ``shape`` for messages: a design's label, a path's
    name (with its sense, ``ccw`` or ``cw``, when the name does not say it)."""
    if not isinstance(shape, EncoderPath):
        return shape.label()
    path = shape
    name = path.name or f"path of {path.legs.length_m.size} legs"
    net = path.net_turn_rad
    if net != 0.0 and not any(word in name for word in ("cw", "clockwise")):
        name += " ccw" if net > 0 else " cw"
    return name


# --- the robot ----------------------------------------------------------------


@dataclass(frozen=True)
class RobotModel:
    """What the information of a plan depends on besides the plan.

    Attributes:
        params: the four parameters at which the information is evaluated (SI).
        turns_exact: whether the robot's turns carry no error (the four
            parameters only).
        turns: the turn errors at which it is evaluated (ignored when
            ``turns_exact``).
        split_directions: one e_turn per kind and direction (else per kind).
        description: floor marks (screws, cross distances, tape sigma) whose
            covariance the information averages over (None: ``measurement_cov``).
        measurement_cov: one (3, 3) covariance of every measured pose change
            (m^2, m rad, rad^2; None with no description: exact poses).
        n_samples, seed: the floor-mark covariance's sample of pose changes.
    """

    params: ErrorParameters
    turns_exact: bool = True
    turns: TurnErrors = DEFAULT_TURN_PRIOR
    split_directions: bool = False
    description: RobotDescription | None = field(default=None, compare=False)
    measurement_cov: FloatArray | None = field(default=None, compare=False)
    n_samples: int = DEFAULT_POSE_SAMPLES
    seed: int = 0

    def __post_init__(self) -> None:
        if self.n_samples < 1:
            raise ParameterError(f"n_samples must be at least 1, got {self.n_samples}")
        if self.measurement_cov is not None:
            cov = np.asarray(self.measurement_cov, dtype=np.float64)
            if cov.shape != (3, 3) or not np.all(np.isfinite(cov)):
                raise ParameterError(
                    f"measurement_cov must be a finite (3, 3) array, got shape {cov.shape}"
                )
            object.__setattr__(self, "measurement_cov", 0.5 * (cov + cov.T))
        if not (math.isfinite(self.turns.k_spin) and self.turns.k_spin >= 0):
            raise ParameterError(f"K_spin is a variance rate, >= 0; got {self.turns.k_spin!r}")

    @classmethod
    def of(
        cls,
        description: RobotDescription,
        *,
        turns: TurnErrors = DEFAULT_TURN_PRIOR,
        split_directions: bool = False,
    ) -> RobotModel:
        """A robot description's model: its ``[priors]``, its ``turns_exact``
        and its floor marks."""
        return cls(
            params=description.priors.mean,
            turns_exact=description.robot.turns_exact,
            turns=turns,
            split_directions=split_directions,
            description=description,
        )

    @property
    def turn_groups(self) -> tuple[tuple[str, tuple[int, ...]], ...]:
        """Per turn-scale parameter, its name and the turn classes it covers
        (rows of odohil/science/paths.py TURN_CLASSES); empty when turns are exact."""
        if self.turns_exact:
            return ()
        if self.split_directions:
            return tuple(
                (f"e_turn_{label.replace(' ', '_')}", (row,))
                for row, label in enumerate(TURN_CLASSES)
            )
        return (("e_turn_spin", (0, 1)), ("e_turn_arc", (2, 3)))

    @property
    def names(self) -> tuple[str, ...]:
        """The parameters, in the order of every array of this module."""
        if self.turns_exact:
            return PARAMETER_NAMES
        return (*PARAMETER_NAMES, *(name for name, _ in self.turn_groups), "K_spin")

    def columns(self) -> list[list[int]]:
        """Per parameter, the columns of odohil/science/moments.py BATCH_COLUMNS it sets."""
        out = [[0], [1], [2], [3]]
        if self.turns_exact:
            return out
        out += [[4 + row for row in rows] for _, rows in self.turn_groups]
        out.append([BATCH_COLUMNS.index("K_spin")])
        return out

    def row(self) -> FloatArray:
        """The parameter row (9,) of :func:`~odohil.science.moments.batch_moments` (SI)."""
        row = np.zeros(len(BATCH_COLUMNS))
        row[:4] = self.params.as_tuple()
        if not self.turns_exact:
            row[4:8] = self.turns.scales
            row[8] = self.turns.k_spin
        return row

    def values(self) -> FloatArray:
        """The parameters' values (p,), SI (a turn-scale group: its first class's)."""
        row = self.row()
        return np.array([row[cols[0]] for cols in self.columns()])

    def scales(self) -> FloatArray:
        """Typical magnitudes (p,) of the parameters (SI)."""
        return np.array([_scale(name) for name in self.names])

    def measurement(self, mean: FloatArray, cov: FloatArray) -> FloatArray:
        """The measurement covariance (3, 3) or stack (n, 3, 3) of a trial whose
        model pose change is N(mean, cov) (module docstring)."""
        if self.description is not None:
            normals = np.random.default_rng(self.seed).standard_normal((self.n_samples, 3))
            values, vectors = np.linalg.eigh(0.5 * (cov + cov.T))
            root = vectors * np.sqrt(np.clip(values, 0.0, None))
            return measurement_covariance(self.description, mean + normals @ root.T)
        if self.measurement_cov is not None:
            return np.asarray(self.measurement_cov, dtype=np.float64)
        return np.zeros((3, 3))


def _scale(name: str) -> float:
    if name in PARAMETER_NAMES:
        return PARAMETER_SCALES[PARAMETER_NAMES.index(name)]
    return TURN_SCALES[units.parameter_kind(name)]


def _is_rate(name: str) -> bool:
    return name in ("K_theta", "K_rho", "K_spin")


# --- information ----------------------------------------------------------------


def path_informations(paths: Sequence[EncoderPath], robot: RobotModel) -> FloatArray:
    """Fisher information (T, p, p) of one trial of each path, SI, in the
    order of :attr:`RobotModel.names` (module docstring).

    Raises:
        ParameterError: no path, or a total covariance that is singular
            (K_theta = 0 with exact poses).
    """
    if not paths:
        raise ParameterError("a plan needs at least one path")
    names = robot.names
    base = robot.row()
    rows = [base]
    steps: list[tuple[float, bool]] = []
    for name, cols in zip(names, robot.columns(), strict=True):
        value = float(base[cols[0]])
        step = _RELATIVE_STEP * max(abs(value), _scale(name))
        one_sided = _is_rate(name) and value - step < 0.0
        for offset in (1.0, 2.0) if one_sided else (1.0, -1.0):
            shifted = base.copy()
            shifted[cols] += offset * step
            rows.append(shifted)
        steps.append((step, one_sided))
    means, covs = batch_moments(PathSet.of(tuple(paths)), np.array(rows))
    p = len(names)
    d_mean = np.empty((p, *means.shape[1:]))
    d_cov = np.empty((p, *covs.shape[1:]))
    for a, (step, one_sided) in enumerate(steps):
        first, second = 1 + 2 * a, 2 + 2 * a
        if one_sided:
            d_mean[a] = (-1.5 * means[0] + 2.0 * means[first] - 0.5 * means[second]) / step
            d_cov[a] = (-1.5 * covs[0] + 2.0 * covs[first] - 0.5 * covs[second]) / step
        else:
            d_mean[a] = 0.5 * (means[first] - means[second]) / step
            d_cov[a] = 0.5 * (covs[first] - covs[second]) / step
    out = np.empty((len(paths), p, p))
    for t in range(len(paths)):
        derivatives = MomentDerivatives(
            mean=means[0, t], cov=covs[0, t], d_mean=d_mean[:, t], d_cov=d_cov[:, t]
        )
        out[t] = trial_information(derivatives, robot.measurement(means[0, t], covs[0, t]))
    return out


def plan_information(items: Sequence[tuple[Shape, int]], robot: RobotModel) -> FloatArray:
    """Fisher information (p, p) of a plan: the sum over its items of the
    number of trials times one trial's (SI, :attr:`RobotModel.names` order).

    Raises:
        ParameterError: an empty plan or a negative count.
    """
    checked = checked_items(items)
    paths = [shape_path(shape) for shape, _ in checked]
    per_trial = path_informations(paths, robot)
    counts = np.array([n for _, n in checked], dtype=np.float64)
    info: FloatArray = np.einsum("t,tij->ij", counts, per_trial)
    return info


def checked_items(items: Sequence[tuple[Shape, int]]) -> list[tuple[Shape, int]]:
    """``items`` as a list, checked: at least one, no negative count.

    Raises:
        ParameterError: an empty plan or a negative count.
    """
    if not items:
        raise ParameterError("a plan needs at least one shape")
    for shape, n in items:
        if n < 0:
            raise ParameterError(f"{shape_label(shape)}: n must be non-negative, got {n}")
    return list(items)


def driven_items(items: Sequence[tuple[Shape, int]]) -> list[tuple[Shape, int]]:
    """The items of a checked plan (:func:`checked_items`) with at least one trial.

    Raises:
        ParameterError: an empty plan, a negative count, or no trial at all.
    """
    driven = [(shape, n) for shape, n in checked_items(items) if n > 0]
    if not driven:
        raise ParameterError("a plan needs at least one trial")
    return driven


# --- what acts, what is identified --------------------------------------------


def acting(paths: Sequence[EncoderPath], robot: RobotModel) -> dict[str, str]:
    """The parameters that do not act on trials of ``paths``, each with the
    reason (the turn errors of kinds of turn the paths do not make)."""
    if robot.turns_exact:
        return {}
    turned = np.zeros(4)
    spun = 0.0
    for path in paths:
        turned += path.turns.total_abs_rad
        spun += path.turns.spin_total_rad
    idle: dict[str, str] = {}
    for name, rows in robot.turn_groups:
        if not any(turned[row] > 0 for row in rows):
            if rows == (0, 1):
                kinds = "spins (turns in place)"
            elif rows == (2, 3):
                kinds = "arcs (curves)"
            else:
                kinds = " or ".join(_KIND_WORDS[TURN_CLASSES[row]] for row in rows)
            idle[name] = f"the plan makes no {kinds}, so it does not act on its trials"
    if spun <= 0.0:
        idle["K_spin"] = "the plan makes no spins, so it does not act on its trials"
    return idle


@dataclass(frozen=True)
class ParameterScore:
    """One parameter's fate in a plan.

    Attributes:
        name: the parameter (:attr:`RobotModel.names`).
        standard_error: its Cramer-Rao standard error, SI; math.inf when not
            estimable.
        reason: why it is not estimable ("" when it is).
        note: what to know of an estimable one (a near-confounding), or "".
    """

    name: str
    standard_error: float
    reason: str = ""
    note: str = ""

    @property
    def estimable(self) -> bool:
        """Whether the plan identifies it."""
        return not self.reason


@dataclass(frozen=True)
class PlanScore:
    """A plan's expected precision and what it can estimate.

    Attributes:
        labels: each item's shape label; counts: its number of trials.
        parameters: per parameter, in :attr:`RobotModel.names` order.
        information: (p, p) Fisher information, SI.
        correlation: (p, p) correlations of the identified parameters'
            estimates (nan for the others).
        seconds: operator time of the plan (:func:`plan_seconds`), s.
        distance_m: metres driven.
    """

    labels: tuple[str, ...]
    counts: tuple[int, ...]
    parameters: tuple[ParameterScore, ...]
    information: FloatArray = field(compare=False, repr=False)
    correlation: FloatArray = field(compare=False, repr=False)
    seconds: float = 0.0
    distance_m: float = 0.0

    @property
    def names(self) -> tuple[str, ...]:
        """The parameters' names."""
        return tuple(p.name for p in self.parameters)

    @property
    def standard_errors(self) -> FloatArray:
        """(p,) Cramer-Rao standard errors, SI (math.inf: not estimable)."""
        return np.array([p.standard_error for p in self.parameters])

    @property
    def estimable(self) -> tuple[str, ...]:
        """The parameters the plan identifies."""
        return tuple(p.name for p in self.parameters if p.estimable)

    @property
    def not_estimable(self) -> tuple[str, ...]:
        """The parameters it does not."""
        return tuple(p.name for p in self.parameters if not p.estimable)

    def parameter(self, name: str) -> ParameterScore:
        """The score of parameter ``name``.

        Raises:
            ParameterError: no such parameter in this plan's model.
        """
        for p in self.parameters:
            if p.name == name:
                return p
        raise ParameterError(f"no parameter {name!r}; the plan's are {', '.join(self.names)}")


def identify(
    information: FloatArray, robot: RobotModel, idle: dict[str, str] | None = None
) -> tuple[tuple[ParameterScore, ...], FloatArray]:
    """Which parameters an information (p, p) identifies, their standard
    errors (SI) and correlations (module docstring); ``idle``: the parameters
    that do not act, with the reason (:func:`acting`)."""
    names = robot.names
    idle = idle or {}
    p = len(names)
    info = 0.5 * (information + information.T)
    scale = robot.scales()
    scaled = info * np.outer(scale, scale)
    acts = [a for a in range(p) if names[a] not in idle]
    top = max((float(scaled[a, a]) for a in acts), default=0.0)
    reasons: dict[int, str] = {
        a: "no information from these trials"
        for a in acts
        if not scaled[a, a] > NO_INFORMATION * top
    }
    live = [a for a in acts if a not in reasons]
    root = np.sqrt(np.diag(scaled)[live])
    corr_info = scaled[np.ix_(live, live)] / np.outer(root, root)
    values, vectors = np.linalg.eigh(corr_info)
    null = values <= SINGULAR * max(float(values[-1]), 1.0) if live else np.zeros(0, dtype=bool)
    null_vectors = vectors[:, null]
    for i, a in enumerate(live):
        if np.linalg.norm(null_vectors[i]) <= _NULL_LEAN:
            continue
        partners = sorted(
            {
                names[live[j]]
                for k in range(null_vectors.shape[1])
                if abs(null_vectors[i, k]) > _NULL_MEMBER
                for j in range(len(live))
                if j != i and abs(null_vectors[j, k]) > _NULL_MEMBER
            },
            key=names.index,
        )
        with_whom = f" with {units.join_words(partners)}" if partners else ""
        reasons[a] = f"confounded{with_whom}: these trials identify only a combination"
    keep = ~null
    # covariance of the estimates: the pseudo-inverse on the identified subspace
    inverse = (vectors[:, keep] / values[keep]) @ vectors[:, keep].T
    unit = scale[live] / root
    cov = np.full((p, p), np.nan)
    cov[np.ix_(live, live)] = inverse * np.outer(unit, unit)
    identified = [a for a in live if a not in reasons]
    errors = np.full(p, math.inf)
    for a in identified:
        errors[a] = math.sqrt(max(float(cov[a, a]), 0.0))
    corr = np.full((p, p), np.nan)
    for a in identified:
        for b in identified:
            corr[a, b] = cov[a, b] / (errors[a] * errors[b]) if errors[a] * errors[b] > 0 else 0.0
    scores = []
    for a, name in enumerate(names):
        if name in idle:
            scores.append(ParameterScore(name, math.inf, idle[name]))
        elif a in reasons:
            scores.append(ParameterScore(name, math.inf, reasons[a]))
        else:
            close = [
                f"{names[b]} ({corr[a, b]:+.3f})"
                for b in identified
                if b != a and abs(corr[a, b]) > CONFOUNDED
            ]
            note = f"nearly confounded with {units.join_words(close)}" if close else ""
            scores.append(ParameterScore(name, float(errors[a]), "", note))
    return tuple(scores), corr


def path_seconds(path: EncoderPath, operator: OperatorTime) -> float:
    """Operator seconds of one trial of ``path``: marking and measuring, the
    distance at the driving speed, and the spins at the turn rate (an arc
    turns while it drives)."""
    spun = sum(abs(s.angle_rad) for s in path.steps if isinstance(s, Turn) and s.kind == "spin")
    return (
        operator.seconds_per_trial
        + path.distance_m / operator.speed_m_per_s
        + spun / operator.turn_rate_rad_per_s
    )


def score_plan(
    items: Sequence[tuple[Shape, int]],
    robot: RobotModel,
    operator: OperatorTime | None = None,
) -> PlanScore:
    """A plan's expected standard errors (Cramer-Rao, SI) and which
    parameters it cannot estimate, with the reason (module docstring).

    Raises:
        ParameterError: an empty plan, a negative count, or a singular total
            covariance (K_theta = 0 with exact poses).
    """
    checked = driven_items(items)
    paths = [shape_path(shape) for shape, _ in checked]
    info = plan_information(checked, robot)
    scores, corr = identify(info, robot, acting(paths, robot))
    seconds = (
        sum(n * path_seconds(path, operator) for path, (_, n) in zip(paths, checked, strict=True))
        if operator is not None
        else 0.0
    )
    return PlanScore(
        labels=tuple(shape_label(shape) for shape, _ in checked),
        counts=tuple(n for _, n in checked),
        parameters=scores,
        information=info,
        correlation=corr,
        seconds=seconds,
        distance_m=sum(n * path.distance_m for path, (_, n) in zip(paths, checked, strict=True)),
    )


def describe_plan(score: PlanScore) -> str:
    """``n x label; ...`` and the time, minutes."""
    items = "; ".join(f"{n} x {label}" for label, n in zip(score.labels, score.counts, strict=True))
    return f"{items} ({score.seconds / 60.0:.0f} min)"
