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

**Plans in a time budget.** :func:`best_plan` searches mixtures of shapes
within an operator time (:func:`path_seconds`: marking and measuring, driving,
spinning); :func:`compare_with_paths` compares the best turn-free plan, the
best forth-and-back plan and the best plan with the given general shapes of
the same time, and says per parameter what the general shapes buy
(:class:`PathComparison`). :func:`plan_estimability` is the pre-flight's
statement of what a plan can and cannot estimate (odohil/session/plans/checks.py).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import numpy as np
import numpy.typing as npt

from odohil import units
from odohil.errors import ParameterError
from odohil.science import targets
from odohil.science.fisher import (
    DEFAULT_POSE_SAMPLES,
    PARAMETER_SCALES,
    MomentDerivatives,
    measurement_covariance,
    trial_information,
)
from odohil.science.moments import BATCH_COLUMNS, PathSet, TurnErrors, batch_moments
from odohil.science.parameters import PARAMETER_NAMES, ErrorParameters
from odohil.science.paths import TURN_CLASSES, Design, Drivable, EncoderPath, FloatArray, Turn
from odohil.science.planner import DEFAULT_MIN_TRIALS_PER_DESIGN, OperatorTime
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
    checked = _checked(items)
    paths = [shape_path(shape) for shape, _ in checked]
    per_trial = path_informations(paths, robot)
    counts = np.array([n for _, n in checked], dtype=np.float64)
    info: FloatArray = np.einsum("t,tij->ij", counts, per_trial)
    return info


def _checked(items: Sequence[tuple[Shape, int]]) -> list[tuple[Shape, int]]:
    if not items:
        raise ParameterError("a plan needs at least one shape")
    for shape, n in items:
        if n < 0:
            raise ParameterError(f"{shape_label(shape)}: n must be non-negative, got {n}")
    return list(items)


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
        with_whom = f" with {_join(partners)}" if partners else ""
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
            note = f"nearly confounded with {_join(close)}" if close else ""
            scores.append(ParameterScore(name, float(errors[a]), "", note))
    return tuple(scores), corr


def _join(words: Sequence[str]) -> str:
    if len(words) <= 1:
        return "".join(words)
    return ", ".join(words[:-1]) + " and " + words[-1]


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
    checked = [(shape, n) for shape, n in _checked(items) if n > 0]
    if not checked:
        raise ParameterError("a plan needs at least one trial")
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


# --- the best plan in a time budget, and what general paths buy -----------------

DEFAULT_K_VALUES: tuple[float, ...] = (0.5, 1.0, 2.0, 5.0, 10.0)
DEFAULT_LEG_LENGTHS_M: tuple[float, ...] = (0.5, 1.0, 2.0, 4.0)
"""The forth-and-back designs a comparison searches by default (both variants)."""
E_TURN_TARGET = (0.25, 1e-3)
"""Default target of a turn-scale error's standard error: max(25 % of
|e_turn|, 0.1 %) (as odohil/science/targets.py for the four)."""
K_SPIN_TARGET = (0.5, 1e-6)
"""Default target of K_spin's standard error: max(50 % of K_spin, 1e-6 rad^2/rad)."""
SHARE_STEPS = 12
"""A mixture's time is shared among its items in steps of 1/SHARE_STEPS."""
POOL_SIZE = 10
"""Items mixed: the best this many alone, and the best two per parameter per second."""
_TIE_BREAK = 1e-3


def default_design_grid() -> list[Design]:
    """Every design of :data:`DEFAULT_K_VALUES` x :data:`DEFAULT_LEG_LENGTHS_M`,
    both variants."""
    return [
        Design(k, length, variant)
        for k in DEFAULT_K_VALUES
        for length in DEFAULT_LEG_LENGTHS_M
        for variant in ("reverse", "turn")
    ]


def default_targets(robot: RobotModel) -> FloatArray:
    """The target standard error (p,) of every parameter at the robot's values
    (SI): odohil/science/targets.py for the four, :data:`E_TURN_TARGET` and
    :data:`K_SPIN_TARGET` for the turn errors."""
    four = targets.default_targets(robot.params)
    out = []
    for name, value in zip(robot.names, robot.values(), strict=True):
        if name in four:
            out.append(four[name])
        elif name == "K_spin":
            out.append(max(K_SPIN_TARGET[0] * abs(value), K_SPIN_TARGET[1]))
        else:
            out.append(max(E_TURN_TARGET[0] * abs(value), E_TURN_TARGET[1]))
    return np.array(out)


@dataclass(frozen=True)
class _Item:
    shape: Shape
    info: FloatArray  # one trial, (p, p)
    seconds: float


def _batch_errors(info: FloatArray, scale: FloatArray) -> FloatArray:
    """Standard errors (B, w) of informations (B, w, w); inf where singular
    (in correlation form, :data:`SINGULAR`)."""
    scaled = info * np.outer(scale, scale)
    diag = np.einsum("bii->bi", scaled)
    positive = np.all(diag > 0, axis=1)
    root = np.sqrt(np.where(diag > 0, diag, 1.0))
    corr = scaled / (root[:, :, None] * root[:, None, :])
    eigen = np.linalg.eigvalsh(corr)
    ok = positive & (eigen[:, 0] > SINGULAR * eigen[:, -1])
    safe = np.where(ok[:, None, None], corr, np.eye(info.shape[1]))
    variances = np.einsum("bii->bi", np.linalg.inv(safe)) / root**2
    errors: FloatArray = np.sqrt(np.abs(variances)) * scale
    errors[~ok] = math.inf
    return errors


def _shares(size: int) -> FloatArray:
    """Every split of 1 into ``size`` positive multiples of 1/SHARE_STEPS."""
    if size == 1:
        return np.ones((1, 1))
    rows = [
        (*head, SHARE_STEPS - sum(head))
        for head in _compositions(size - 1, SHARE_STEPS - 1)
        if sum(head) < SHARE_STEPS
    ]
    return np.array(rows, dtype=np.float64) / SHARE_STEPS


def _compositions(parts: int, most: int) -> list[tuple[int, ...]]:
    if parts == 0:
        return [()]
    return [
        (first, *rest)
        for first in range(1, most + 1)
        for rest in _compositions(parts - 1, most - first)
    ]


def best_plan(
    shapes: Sequence[Shape],
    robot: RobotModel,
    budget_s: float,
    *,
    operator: OperatorTime | None = None,
    target_errors: FloatArray | None = None,
    min_trials: int = DEFAULT_MIN_TRIALS_PER_DESIGN,
    max_items: int = 3,
    required: Sequence[Shape] = (),
    max_required: int = 2,
) -> PlanScore | None:
    """The plan of at most ``max_items`` of ``shapes`` (with ``required``:
    one to ``max_required`` of those, and at most ``max_items`` others), each
    at least ``min_trials`` trials, within ``budget_s`` operator seconds, that
    estimates as many as it can of the parameters the shapes together
    identify (the others are reported not estimable), and among those the
    one with the smallest largest ratio of standard error to target over the
    parameters acting on its trials. A grid search: items are the best alone
    and the best per parameter per second (:data:`POOL_SIZE`), the time is
    shared in steps of 1/:data:`SHARE_STEPS`. None when no plan fits.

    Raises:
        ParameterError: no shape, a bad budget or bad counts.
    """
    if not shapes:
        raise ParameterError("the search needs at least one shape")
    if not (math.isfinite(budget_s) and budget_s > 0):
        raise ParameterError(
            f"the time budget must be a positive number of seconds, got {budget_s!r}"
        )
    if min_trials < 1 or not 1 <= max_items <= 3 or not 1 <= max_required <= 2:
        raise ParameterError(
            "min_trials >= 1, 1 <= max_items <= 3 and 1 <= max_required <= 2; got "
            f"{min_trials}, {max_items}, {max_required}"
        )
    operator = operator or OperatorTime()
    wanted_targets = default_targets(robot) if target_errors is None else target_errors
    paths = [shape_path(s) for s in shapes]
    infos = path_informations(paths, robot)
    items = [
        _Item(shape, info, path_seconds(path, operator))
        for shape, info, path in zip(shapes, infos, paths, strict=True)
    ]
    items = [i for i in items if min_trials * i.seconds <= budget_s]
    if not items:
        return None
    # the parameters these shapes can identify at all
    whole = sum((i.info for i in items), np.zeros_like(infos[0]))
    reach, _ = identify(whole, robot, acting([shape_path(i.shape) for i in items], robot))
    wanted = np.array([k for k, s in enumerate(reach) if s.estimable])
    if wanted.size == 0:
        return None
    scale = robot.scales()[wanted]
    divisor = wanted_targets[wanted]
    per_trial = np.array([i.info[np.ix_(wanted, wanted)] for i in items])
    seconds = np.array([i.seconds for i in items])
    wanted_names = [robot.names[k] for k in wanted]
    acts = np.array(
        [[n not in acting([shape_path(i.shape)], robot) for n in wanted_names] for i in items]
    )
    must = {id(s) for s in required}
    needed = [k for k, i in enumerate(items) if id(i.shape) in must] if required else []
    if required and not needed:
        return None
    search = _Search(per_trial, seconds, acts, scale, divisor)
    pool = search.pool(budget_s, needed)
    best: tuple[tuple[int, float], tuple[int, ...], FloatArray] | None = None
    for group in _groups(pool, needed, max_items, max_required):
        shares = _shares(len(group))
        counts = np.floor(shares * budget_s / seconds[list(group)] + 1e-9)
        counts = counts[np.all(counts >= min_trials, axis=1)]
        if counts.size == 0:
            continue
        key, row = search.best(group, counts)
        if math.isfinite(key[1]) and (best is None or key < best[0]):
            best = (key, group, counts[row])
    if best is None:
        return None
    _, group, counts = best
    plan = [(items[k].shape, int(n)) for k, n in zip(group, counts, strict=True)]
    return score_plan(plan, robot, operator)


def _groups(
    pool: Sequence[int], needed: Sequence[int], max_items: int, max_required: int
) -> list[tuple[int, ...]]:
    """The groups of candidates :func:`best_plan` tries."""
    if not needed:
        return [g for size in range(1, max_items + 1) for g in itertools.combinations(pool, size)]
    others = [k for k in pool if k not in set(needed)]
    return [
        (*head, *tail)
        for size in range(1, max_required + 1)
        for head in itertools.combinations(needed, size)
        for extra in range(max_items + 1)
        for tail in itertools.combinations(others, extra)
    ]


@dataclass(frozen=True)
class _Search:
    """The candidates of :func:`best_plan` restricted to the wanted parameters.

    Attributes:
        per_trial: (K, w, w) one trial's information; seconds: (K,) its time.
        acts: (K, w) which wanted parameters act on each candidate's trials.
        scale: (w,) typical magnitudes; divisor: (w,) target standard errors.
    """

    per_trial: FloatArray
    seconds: FloatArray
    acts: npt.NDArray[np.bool_]
    scale: FloatArray
    divisor: FloatArray

    def values(self, total: FloatArray, mask: npt.NDArray[np.bool_]) -> FloatArray:
        """The criterion (B,) of informations (B, w, w) over the parameters
        ``mask`` (those acting): the largest standard error / target ratio
        plus a small tie-break (the RMS ratio); inf where singular."""
        sub = total[:, mask][:, :, mask]
        ratios = _batch_errors(sub, self.scale[mask]) / self.divisor[mask]
        value: FloatArray = ratios.max(axis=1) + _TIE_BREAK * np.sqrt((ratios**2).mean(axis=1))
        return value

    def best(self, group: Sequence[int], counts: FloatArray) -> tuple[tuple[int, float], int]:
        """((wanted parameters not acting, criterion), row) of the best row of
        ``counts`` (B, len(group)): as many wanted parameters as possible, then precision."""
        mask: npt.NDArray[np.bool_] = np.asarray(self.acts[list(group)].any(axis=0), dtype=bool)
        total = np.einsum("bd,dij->bij", counts, self.per_trial[list(group)])
        values = self.values(total, mask)
        row = int(np.argmin(values))
        return (int((~mask).sum()), float(values[row])), row

    def pool(self, budget_s: float, needed: Sequence[int]) -> list[int]:
        """The candidates worth mixing: the best :data:`POOL_SIZE` alone
        (each over the parameters acting on it), the best two per parameter
        per second, and ``needed``."""
        alone = np.floor(budget_s / self.seconds)
        keys = []
        for k in range(len(self.seconds)):
            total = self.per_trial[k][None] * alone[k]
            value = float(self.values(total, self.acts[k])[0])
            keys.append((int((~self.acts[k]).sum()), value))
        chosen = set(sorted(range(len(keys)), key=keys.__getitem__)[:POOL_SIZE])
        per_second = np.einsum("bii->bi", self.per_trial) / self.seconds[:, None]
        for a in range(self.per_trial.shape[1]):
            chosen.update(np.argsort(-per_second[:, a], kind="stable")[:2].tolist())
        chosen.update(needed)
        return sorted(chosen)


@dataclass(frozen=True)
class Gain:
    """What general paths change for one parameter.

    Attributes:
        name: the parameter.
        turn_free, forth_and_back, with_paths: its standard error (SI) in
            each plan of the comparison (math.inf: not estimable).
        newly_estimable: the plan with general paths estimates it and no
            forth-and-back plan of the search does.
        ratio: forth-and-back's standard error over the general paths'
            (> 1: the general paths buy precision; nan when either is not estimable).
    """

    name: str
    turn_free: float
    forth_and_back: float
    with_paths: float

    @property
    def newly_estimable(self) -> bool:
        """Estimable only with the general paths."""
        return math.isinf(self.forth_and_back) and math.isfinite(self.with_paths)

    @property
    def ratio(self) -> float:
        """forth_and_back / with_paths (nan when either is not estimable)."""
        if math.isinf(self.forth_and_back) or math.isinf(self.with_paths):
            return math.nan
        return self.forth_and_back / self.with_paths


MIXED_DESIGNS = 2
"""Most forth-and-back designs beside the general shapes in a comparison's plan."""
BUYS_RATIO = 1.2
"""General paths buy precision in a parameter when they shrink its standard
error by at least this factor at the same time."""


@dataclass(frozen=True)
class PathComparison:
    """What adding general paths (squares, circles) buys over the best
    forth-and-back plans of the same operator time.

    Attributes:
        budget_s: the operator time of every plan, s.
        turn_free: the best plan of turn-free designs (``reverse``; what the
            planner recommends for a robot whose turns carry error).
        forth_and_back: the best forth-and-back plan, turn designs allowed
            (the turn errors estimated, not folded into E_R and K_theta).
        with_paths: the best plan with one or two of the general shapes and
            up to :data:`MIXED_DESIGNS` forth-and-back designs beside them.
        gains: per parameter, what the general paths change.
        findings: the comparison in sentences, paper units.
    """

    budget_s: float
    turn_free: PlanScore | None
    forth_and_back: PlanScore | None
    with_paths: PlanScore | None
    gains: tuple[Gain, ...]
    findings: tuple[str, ...]

    @property
    def buys(self) -> tuple[str, ...]:
        """The parameters the general paths make estimable, or estimate at
        least :data:`BUYS_RATIO` times more precisely."""
        return tuple(g.name for g in self.gains if g.newly_estimable or g.ratio >= BUYS_RATIO)


def compare_with_paths(
    robot: RobotModel,
    general: Sequence[Shape],
    budget_s: float,
    *,
    operator: OperatorTime | None = None,
    designs: Sequence[Design] | None = None,
    target_errors: FloatArray | None = None,
    min_trials: int = DEFAULT_MIN_TRIALS_PER_DESIGN,
    max_items: int = 3,
) -> PathComparison:
    """Compare, at the same operator time, the best turn-free plan, the best
    forth-and-back plan and the best plan that adds ``general`` shapes
    (:func:`best_plan` each), and say per parameter what the general shapes
    buy (module docstring; :class:`PathComparison`).

    Raises:
        ParameterError: no general shape or a bad budget.
    """
    if not general:
        raise ParameterError("the comparison needs at least one general path")
    grid = list(designs) if designs is not None else default_design_grid()

    def search(shapes: Sequence[Shape], required: Sequence[Shape] = ()) -> PlanScore | None:
        if not shapes:
            return None
        return best_plan(
            shapes,
            robot,
            budget_s,
            operator=operator,
            target_errors=target_errors,
            min_trials=min_trials,
            max_items=min(max_items, MIXED_DESIGNS) if required else max_items,
            required=required,
        )

    turn_free = search([d for d in grid if d.variant == "reverse"])
    forth = search(grid)
    mixed = search([*general, *grid], general)
    gains = tuple(
        Gain(
            name,
            _error_of(turn_free, name),
            _error_of(forth, name),
            _error_of(mixed, name),
        )
        for name in robot.names
    )
    return PathComparison(
        budget_s, turn_free, forth, mixed, gains, _findings(robot, turn_free, forth, mixed, gains)
    )


def _error_of(score: PlanScore | None, name: str) -> float:
    return math.inf if score is None else score.parameter(name).standard_error


def _ratio_words(ratio: float) -> str:
    if abs(ratio - 1.0) < 0.05:
        return "about the same"
    if ratio > 1.0:
        return f"{ratio:.2g} times smaller"
    return f"{1.0 / ratio:.2g} times larger"


def describe_plan(score: PlanScore) -> str:
    """``n x label; ...`` and the time, minutes."""
    items = "; ".join(f"{n} x {label}" for label, n in zip(score.labels, score.counts, strict=True))
    return f"{items} ({score.seconds / 60.0:.0f} min)"


def _findings(
    robot: RobotModel,
    turn_free: PlanScore | None,
    forth: PlanScore | None,
    mixed: PlanScore | None,
    gains: Sequence[Gain],
) -> tuple[str, ...]:
    out: list[str] = []
    for title, score in (
        ("turn-free forth-and-back", turn_free),
        ("forth-and-back with turns", forth),
        ("with the general paths", mixed),
    ):
        out.append(f"Best {title}: " + ("none fits" if score is None else describe_plan(score)))
    for gain in gains:
        name = gain.name
        parts: list[str] = []
        if turn_free is not None and math.isinf(gain.turn_free):
            reason = turn_free.parameter(name).reason
            parts.append(f"turn-free designs cannot estimate it: {reason}")
        if forth is not None:
            entry = forth.parameter(name)
            if entry.estimable:
                text = f"forth-and-back SE {units.paper_text(name, gain.forth_and_back)}"
                parts.append(text + (f", {entry.note}" if entry.note else ""))
            else:
                parts.append(f"no forth-and-back plan estimates it: {entry.reason}")
        if mixed is not None:
            entry = mixed.parameter(name)
            if entry.estimable:
                text = f"with the general paths SE {units.paper_text(name, gain.with_paths)}"
                if gain.newly_estimable:
                    text += ": estimable only with them"
                elif math.isfinite(gain.ratio):
                    text += f" ({_ratio_words(gain.ratio)})"
                parts.append(text + (f", {entry.note}" if entry.note else ""))
            else:
                parts.append(f"nor do the general paths: {entry.reason}")
        out.append(f"{name}: " + "; ".join(parts))
    return tuple(out)


# --- what a plan can estimate (the pre-flight statement) ----------------------


@dataclass(frozen=True)
class Estimability:
    """What trials of a plan can and cannot estimate, before any is driven.

    Attributes:
        turns_exact: whether the model has the four parameters only.
        estimable: the parameters the plan identifies.
        standard_errors: their expected (Cramer-Rao) standard errors, SI.
        not_estimable: (parameter, reason) of the others.
        notes: what else to know (near-confoundings, the model).
        problems: why no estimate could come of these trials (empty when one can).
    """

    turns_exact: bool
    estimable: tuple[str, ...]
    standard_errors: tuple[float, ...]
    not_estimable: tuple[tuple[str, str], ...]
    notes: tuple[str, ...] = ()
    problems: tuple[str, ...] = ()

    @property
    def ok(self) -> bool:
        """Whether an estimate can come of these trials."""
        return not self.problems

    def text(self, *, problems: bool = True) -> str:
        """The statement (expected standard errors in paper units), with the
        problems unless ``problems`` is False."""
        found = [
            f"{name} (SE {units.paper_text(name, se)})"
            for name, se in zip(self.estimable, self.standard_errors, strict=True)
        ]
        sentences = [f"Estimates {_join(found) or 'nothing'}"]
        if not self.turns_exact and any(n not in PARAMETER_NAMES for n in self.estimable):
            sentences[0] += ", the turn errors with the four (not folded into E_R and K_theta)"
        if self.not_estimable:
            sentences.append(
                "Cannot estimate "
                + "; ".join(f"{name}: {reason}" for name, reason in self.not_estimable)
            )
        sentences += [*self.notes, *(self.problems if problems else ())]
        return ". ".join(sentences) + "."


def plan_estimability(items: Sequence[tuple[Shape, int]], robot: RobotModel) -> Estimability:
    """What a plan can estimate on ``robot`` (module docstring): the
    parameters it identifies with their expected standard errors, the others
    with the reason, and the problems that leave no estimate at all: one of
    the four not identified, a turn error that acts on the trials but is not
    identified (the estimator fits every turn error whose turns the trials
    make: odohil/science/estimators/paths.py), or no more trials than
    parameters.

    Raises:
        ParameterError: an empty plan or a negative count.
    """
    checked = [(shape, n) for shape, n in _checked(items) if n > 0]
    if not checked:
        raise ParameterError("a plan needs at least one trial")
    score = score_plan(checked, robot)
    acts = acting([shape_path(shape) for shape, _ in checked], robot)
    problems = [
        f"{p.name} is not identified: {p.reason}"
        for p in score.parameters
        if not p.estimable and p.name not in acts
    ]
    fitted = len(robot.names) - len(acts)
    n_trials = sum(n for _, n in checked)
    if n_trials <= fitted:
        problems.append(
            f"{units.plural(n_trials, 'trial')} for {fitted} parameters: need at least {fitted + 1}"
        )
    names = score.names
    corr = score.correlation
    notes = [
        f"{names[a]} and {names[b]} are nearly confounded (correlation {corr[a, b]:+.3f})"
        for a in range(len(names))
        for b in range(a + 1, len(names))
        if abs(corr[a, b]) > CONFOUNDED
    ]
    notes += _split_note(checked, robot)
    kept = [p for p in score.parameters if p.estimable]
    return Estimability(
        turns_exact=robot.turns_exact,
        estimable=tuple(p.name for p in kept),
        standard_errors=tuple(p.standard_error for p in kept),
        not_estimable=tuple((p.name, p.reason) for p in score.parameters if not p.estimable),
        notes=tuple(notes),
        problems=tuple(problems),
    )


def _split_note(items: Sequence[tuple[Shape, int]], robot: RobotModel) -> list[str]:
    """What one e_turn per direction would estimate, for a plan that turns
    both ways with one kind of turn (the estimator splits e_turn by direction
    when a likelihood-ratio test asks for it: odohil/science/estimators/paths.py)."""
    if robot.turns_exact or robot.split_directions:
        return []
    turned = sum((shape_path(shape).turns.total_abs_rad for shape, _ in items), np.zeros(4))
    if not ((turned[0] > 0 and turned[1] > 0) or (turned[2] > 0 and turned[3] > 0)):
        return []
    split = score_plan(items, replace(robot, split_directions=True))
    both = [
        p
        for p in split.parameters
        if p.name.startswith("e_turn") and not p.reason.startswith("the plan makes no")
    ]
    found = [
        f"{p.name} (SE {units.paper_text(p.name, p.standard_error)})" for p in both if p.estimable
    ]
    lost = [f"{p.name}: {p.reason}" for p in both if not p.estimable]
    text = "If the data ask for one e_turn per direction, the split fit estimates " + (
        _join(found) or "none of them"
    )
    return [text + (f"; not {'; '.join(lost)}" if lost else "")]
