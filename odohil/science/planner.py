"""Experiment planner: which forth-and-back designs to drive, and how often.

Inputs: prior guesses of the four parameters, the floor-mark measurement
(a robot description, or a tape sigma with :func:`fisher.default_description`'s
layout), and a budget: metres driven in all and optionally the most trials
that will be marked.

Search: every design of a grid (k from 1/2 to 20 including half-integers,
leg lengths 0.5 m to ``max_leg_m`` and to the free floor, both variants;
without a floor length :data:`DEFAULT_FLOOR_M`) gets its per-trial Fisher
information (:mod:`odohil.science.fisher`); then single designs, pairs and
triples are allocated integer trial counts within the budget, and the plan
with the smallest criterion wins. Pairs and triples are drawn from a pool of
the most promising designs (best single designs overall and per parameter).

Targets: every parameter has one (SI standard errors). Those not given
default to a stated fraction of the prior value (:func:`odohil.science.targets.default_targets`:
25 % of |E_R| and |E_T|, 50 % of K_theta and K_rho, with floors); math.inf
means "no target". A plan "meets the targets" only when every standard error
is at most its target.

Criterion (smaller is better): max_a se_a / target_a, so a value <= 1 meets
every target (ties broken by the root mean square of the ratios).

Honest intervals need trials: every design of a plan gets at least
``min_trials_per_design`` (default :data:`DEFAULT_MIN_TRIALS_PER_DESIGN`;
the estimators' 95 % intervals cover from about 10 trials per design, 5 is
marginal: BENCHMARKS.md).

Operator time (:class:`OperatorTime`): seconds to mark and measure one trial
plus the driving (distance / speed, turns / turn rate), so that plans can be
compared in minutes; ``budget_s`` bounds it like ``budget_m`` bounds metres.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from odohil import units
from odohil.errors import ParameterError
from odohil.science.fisher import (
    PARAMETER_SCALES,
    MeasurementModel,
    moment_derivatives,
    pose_spread_measurement,
    standard_errors,
    trial_information,
)
from odohil.science.parameters import PARAMETER_NAMES, ErrorParameters
from odohil.science.paths import VARIANTS, Design, FloatArray, Turn, floor_choreography
from odohil.science.robot_description import RobotDescription
from odohil.science.targets import default_targets

DEFAULT_K_VALUES: tuple[float, ...] = (0.5, 1.0, 1.5, 2.0, 3.0, 5.0, 10.0, 20.0)
DEFAULT_LEG_LENGTHS_M: tuple[float, ...] = (
    0.5, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 10.0, 12.0, 15.0, 20.0, 25.0, 30.0,
)  # fmt: skip
DEFAULT_MAX_LEG_M = 30.0
DEFAULT_FLOOR_M = 10.0
"""Free floor the default design grid assumes when none is given, metres: no
leg longer, and no plan whose trials (one-way ones alternating, see
:func:`odohil.science.paths.floor_choreography`) cover more."""
MAX_DESIGNS = 3
DEFAULT_MIN_TRIALS_PER_DESIGN = 10
"""Fewest trials of any design in a plan: the estimators' 95 % intervals cover
from about 10 trials per design (5 is marginal; BENCHMARKS.md, bench/coverage.py)."""
DEFAULT_SECONDS_PER_TRIAL = 120.0
"""Operator seconds to mark the start, mark the end and take the tape readings
of one trial (an assumption: time your own and pass it)."""
DEFAULT_SPEED_M_PER_S = 0.5
"""Driving speed of the time model, m/s (the driver's default translation speed)."""
DEFAULT_TURN_RATE_RAD_PER_S = math.radians(45.0)
"""In-place turn rate of the time model, rad/s (the driver's default steering speed)."""
_TIE_BREAK = 1e-3
"""Weight of the RMS of the ratios beside their maximum, so that among plans
with the same worst ratio the one better on the others wins."""
_POOL_SIZE = 24
_GRID_STEPS = 24
"""Trial counts tried per design in a mixture (before the last design takes
what is left of the budget)."""
_SEARCH_ROUNDS = 64
"""Most moves of the local search at one step size."""


@dataclass(frozen=True)
class OperatorTime:
    """How long a trial takes, for comparing plans in minutes.

    Attributes:
        seconds_per_trial: marking and measuring one trial, s.
        speed_m_per_s: driving speed, m/s.
        turn_rate_rad_per_s: in-place turn rate, rad/s.
    """

    seconds_per_trial: float = DEFAULT_SECONDS_PER_TRIAL
    speed_m_per_s: float = DEFAULT_SPEED_M_PER_S
    turn_rate_rad_per_s: float = DEFAULT_TURN_RATE_RAD_PER_S

    def __post_init__(self) -> None:
        if not math.isfinite(self.seconds_per_trial) or self.seconds_per_trial < 0:
            raise ParameterError(
                f"seconds per trial must be a non-negative number, got {self.seconds_per_trial!r}"
            )
        for name in ("speed_m_per_s", "turn_rate_rad_per_s"):
            value = getattr(self, name)
            if not math.isfinite(value) or value <= 0:
                raise ParameterError(f"{name} must be a positive number, got {value!r}")

    def trial_seconds(self, design: Design) -> float:
        """Seconds for one trial of ``design``: marking and measuring, driving
        2kl metres, and its in-place turns."""
        turns = sum(abs(s.angle_rad) for s in design.path().steps if isinstance(s, Turn))
        return (
            self.seconds_per_trial
            + design.distance_m / self.speed_m_per_s
            + turns / self.turn_rate_rad_per_s
        )


@dataclass(frozen=True)
class PlanItem:
    """One design of a plan and how many trials of it to drive."""

    design: Design
    n_trials: int

    @property
    def distance_m(self) -> float:
        """Metres driven by all trials of this design."""
        return self.n_trials * self.design.distance_m


@dataclass(frozen=True)
class Plan:
    """A recommended (or evaluated) experiment.

    Attributes:
        items: designs and their trial counts.
        standard_errors: (4,) expected standard errors (Cramer-Rao, SI) of
            E_R rad/m, E_T, K_theta rad^2/m, K_rho m.
        criterion: the largest standard error / target ratio; <= 1 meets
            every target.
        targets: the target of every parameter (SI; math.inf: none).
        operator: the time model.
        min_trials_per_design: the fewest trials of a design for honest intervals.
        notes: what the plan should know (e.g. a design below the minimum).
    """

    items: tuple[PlanItem, ...]
    standard_errors: FloatArray
    criterion: float
    targets: Mapping[str, float]
    operator: OperatorTime = OperatorTime()
    min_trials_per_design: int = DEFAULT_MIN_TRIALS_PER_DESIGN
    notes: tuple[str, ...] = ()

    @property
    def distance_m(self) -> float:
        """Total metres driven."""
        return sum(item.distance_m for item in self.items)

    @property
    def n_trials(self) -> int:
        """Total number of trials (each marked and measured)."""
        return sum(item.n_trials for item in self.items)

    @property
    def duration_s(self) -> float:
        """Operator time of the whole plan, s (:class:`OperatorTime`)."""
        return sum(i.n_trials * self.operator.trial_seconds(i.design) for i in self.items)

    @property
    def unmet(self) -> tuple[str, ...]:
        """The parameters whose standard error exceeds its target."""
        return tuple(
            name
            for name, se in zip(PARAMETER_NAMES, self.standard_errors, strict=True)
            if not se <= self.targets.get(name, math.inf)
        )

    @property
    def meets_targets(self) -> bool:
        """True when every parameter's standard error is at most its target."""
        return not self.unmet

    @property
    def honest(self) -> bool:
        """Every design has at least ``min_trials_per_design`` trials."""
        return all(i.n_trials >= self.min_trials_per_design for i in self.items)

    def designs(self) -> list[tuple[Design, int]]:
        """(design, n_trials) pairs, as :func:`fisher.fisher_information` takes them."""
        return [(item.design, item.n_trials) for item in self.items]

    @property
    def excursion_m(self) -> float:
        """Free floor the plan needs, metres, driven in item order with
        alternating directions (:func:`odohil.science.paths.floor_choreography`)."""
        return floor_choreography(self.designs()).excursion_m


@dataclass(frozen=True)
class _Candidate:
    design: Design
    info: FloatArray  # per trial, (4, 4)
    seconds: float = 0.0  # operator time of one trial


def measurement_model(
    description: RobotDescription | None, prior: ErrorParameters
) -> MeasurementModel:
    """The Fisher measurement model for a robot description (None: exact poses)."""
    if description is None:
        return None
    return pose_spread_measurement(description, prior)


def check_targets(targets: Mapping[str, float] | None) -> dict[str, float]:
    """Validated targets: names among E_R, E_T, K_theta, K_rho; positive SI
    values (math.inf: no target)."""
    checked: dict[str, float] = {}
    for name, value in (targets or {}).items():
        if name not in PARAMETER_NAMES:
            raise ParameterError(f"unknown target {name!r}; choose from {PARAMETER_NAMES}")
        if math.isnan(value) or value <= 0:
            raise ParameterError(f"target for {name} must be a positive number, got {value!r}")
        checked[name] = float(value)
    return checked


def complete_targets(
    prior: ErrorParameters, targets: Mapping[str, float] | None = None
) -> dict[str, float]:
    """A target for every parameter: those given (checked), the others
    :func:`odohil.science.targets.default_targets` at the prior."""
    return {**default_targets(prior), **check_targets(targets)}


def _divisor(targets: Mapping[str, float]) -> FloatArray:
    return np.array([targets[name] for name in PARAMETER_NAMES], dtype=np.float64)


def criterion_value(errors: FloatArray, divisor: FloatArray) -> FloatArray:
    """The search criterion of standard errors (..., 4): the largest ratio to
    the target, plus :data:`_TIE_BREAK` times the RMS of the ratios."""
    ratios = errors / divisor
    worst = np.max(ratios, axis=-1)
    return worst + _TIE_BREAK * np.sqrt(np.mean(ratios**2, axis=-1))  # type: ignore[no-any-return]


def max_ratio(errors: FloatArray, targets: Mapping[str, float]) -> float:
    """The largest standard error / target ratio (the plan's criterion)."""
    return float(np.max(np.asarray(errors) / _divisor(targets)))


def design_grid(
    k_values: Sequence[float] = DEFAULT_K_VALUES,
    leg_lengths_m: Sequence[float] = DEFAULT_LEG_LENGTHS_M,
    max_leg_m: float = DEFAULT_MAX_LEG_M,
    budget_m: float = math.inf,
) -> list[Design]:
    """Every design of the grid whose leg fits ``max_leg_m`` and whose one
    trial fits the budget (metres)."""
    designs = []
    for k, length, variant in itertools.product(k_values, leg_lengths_m, VARIANTS):
        design = Design(k, length, variant)
        if length <= max_leg_m and design.distance_m <= budget_m:
            designs.append(design)
    return designs


@dataclass(frozen=True)
class _Budget:
    """The limits of a plan: metres, trials, operator seconds, and the fewest
    trials of a design."""

    metres: float
    trials: int
    seconds: float
    min_n: int

    def most(self, candidate: _Candidate) -> int:
        """Most trials of one design alone."""
        by_time = self.seconds / candidate.seconds if candidate.seconds > 0 else math.inf
        high = min(float(self.trials), self.metres / candidate.design.distance_m + 1e-9, by_time)
        return int(min(math.floor(high + 1e-9), 10**9))

    def fits(self, group: Sequence[_Candidate]) -> bool:
        """Whether every design of ``group`` can have ``min_n`` trials."""
        return (
            self.min_n * len(group) <= self.trials
            and self.min_n * sum(c.design.distance_m for c in group) <= self.metres * (1 + 1e-12)
            and self.min_n * sum(c.seconds for c in group) <= self.seconds * (1 + 1e-12)
        )


def plan_experiment(
    prior: ErrorParameters,
    budget_m: float,
    *,
    max_trials: int | None = None,
    description: RobotDescription | None = None,
    targets: Mapping[str, float] | None = None,
    max_designs: int = 2,
    designs: Sequence[Design] | None = None,
    max_leg_m: float = DEFAULT_MAX_LEG_M,
    floor_m: float | None = None,
    min_trials_per_design: int = DEFAULT_MIN_TRIALS_PER_DESIGN,
    operator: OperatorTime | None = None,
    budget_s: float | None = None,
) -> Plan:
    """Recommend designs and trial counts within a budget.

    Args:
        prior: guessed parameter values (SI); the information is evaluated there.
        budget_m: most metres driven in all (math.inf with a ``budget_s``).
        max_trials: most trials in all (each must be marked and measured).
        description: floor-mark measurement (None: exact pose changes).
        targets: wanted standard errors (SI) by parameter name; the others
            default to :func:`complete_targets`.
        max_designs: mixtures of at most this many designs (1 to 3).
        designs: the candidate designs (default: :func:`design_grid`, its
            ``reverse`` designs only for a robot whose turns carry error,
            ``[robot] turns_exact = false``).
        max_leg_m: longest leg allowed, metres (for the default grid).
        floor_m: free floor, metres: no plan covers more (see
            :attr:`Plan.excursion_m`). None: :data:`DEFAULT_FLOOR_M` for the
            default grid, no limit for given ``designs``.
        min_trials_per_design: fewest trials of each design of the plan.
        operator: the time model (default :class:`OperatorTime`).
        budget_s: most operator seconds in all (None: no limit).

    Raises:
        ParameterError: bad budget, no design fits it, or bad targets.
    """
    if floor_m is not None and (not math.isfinite(floor_m) or floor_m <= 0):
        raise ParameterError(f"the floor must be a positive number of metres, got {floor_m!r}")
    floor = floor_m if floor_m is not None else (DEFAULT_FLOOR_M if designs is None else math.inf)
    seconds = math.inf if budget_s is None else budget_s
    if math.isnan(seconds) or seconds <= 0:
        raise ParameterError(
            f"the time budget must be a positive number of seconds, got {budget_s!r}"
        )
    if math.isnan(budget_m) or budget_m <= 0 or (math.isinf(budget_m) and math.isinf(seconds)):
        raise ParameterError(f"the budget must be a positive number of metres, got {budget_m!r}")
    if max_trials is not None and max_trials < 1:
        raise ParameterError(f"max_trials must be at least 1, got {max_trials}")
    if not 1 <= max_designs <= MAX_DESIGNS:
        raise ParameterError(f"max_designs must be 1 to {MAX_DESIGNS}, got {max_designs}")
    if min_trials_per_design < 1:
        raise ParameterError(
            f"the fewest trials per design must be at least 1, got {min_trials_per_design}"
        )
    if max_trials is not None and max_trials < min_trials_per_design:
        raise ParameterError(
            f"max_trials {max_trials} is below the "
            f"{units.plural(min_trials_per_design, 'trial')} a design "
            "needs for honest intervals"
        )
    operator = operator or OperatorTime()
    checked = complete_targets(prior, targets)
    budget = _Budget(
        budget_m, max_trials if max_trials is not None else 10**6, seconds, min_trials_per_design
    )
    pool = list(designs) if designs is not None else design_grid(max_leg_m=max_leg_m)
    if designs is None and description is not None and not description.robot.turns_exact:
        pool = [d for d in pool if d.variant != "turn"]  # spins carry error: turn-free only
    pool = [d for d in pool if d.l_m <= floor]
    fitting = [
        d for d in pool if budget.fits([_Candidate(d, np.zeros((4, 4)), operator.trial_seconds(d))])
    ]
    if not fitting:
        raise ParameterError(
            f"no candidate design fits {units.plural(min_trials_per_design, 'trial')} "
            "(the fewest per design "
            f"for honest intervals) in a budget of {budget_m:g} m"
            + ("" if budget_s is None else f" and {budget_s / 60:g} min")
            + f" and {floor:g} m of floor"
        )
    model = measurement_model(description, prior)
    candidates = [_candidate(design, prior, model, operator) for design in fitting]
    divisor = _divisor(checked)

    best: tuple[float, tuple[PlanItem, ...], FloatArray] | None = None
    for size in range(1, max_designs + 1):
        for group in _groups(candidates, size, budget, divisor):
            result = _allocate(group, budget, divisor)
            if result is None or (best is not None and result[0] >= best[0]):
                continue
            if floor_choreography([(i.design, i.n_trials) for i in result[1]]).excursion_m > floor:
                continue
            best = result
    if best is None:
        raise ParameterError("no plan within the budget identifies all four parameters")
    _, items, errors = best
    return Plan(
        items=items,
        standard_errors=errors,
        criterion=max_ratio(errors, checked),
        targets=checked,
        operator=operator,
        min_trials_per_design=min_trials_per_design,
    )


def evaluate_plan(
    designs: Sequence[tuple[Design, int]],
    prior: ErrorParameters,
    *,
    description: RobotDescription | None = None,
    targets: Mapping[str, float] | None = None,
    min_trials_per_design: int = DEFAULT_MIN_TRIALS_PER_DESIGN,
    operator: OperatorTime | None = None,
) -> Plan:
    """Score a plan one wrote: its expected standard errors (the same
    measurement model as the planner), targets, time, and a note for each
    design below ``min_trials_per_design``.

    Raises:
        ParameterError: an empty plan, a count below 1, or bad targets.
    """
    if not designs:
        raise ParameterError("the plan to evaluate has no design")
    for design, n in designs:
        if n < 1:
            raise ParameterError(f"{design.label()}: n must be at least 1, got {n}")
    checked = complete_targets(prior, targets)
    errors = expected_standard_errors(designs, prior, description)
    notes = tuple(
        f"{design.label()}: {units.plural(n, 'trial')}, below the "
        f"{min_trials_per_design} a design needs for "
        "honest 95 % intervals"
        for design, n in designs
        if n < min_trials_per_design
    )
    return Plan(
        items=tuple(PlanItem(design, n) for design, n in designs),
        standard_errors=errors,
        criterion=max_ratio(errors, checked),
        targets=checked,
        operator=operator or OperatorTime(),
        min_trials_per_design=min_trials_per_design,
        notes=notes,
    )


def minimum_budget(
    prior: ErrorParameters,
    targets: Mapping[str, float],
    *,
    max_trials: int | None = None,
    description: RobotDescription | None = None,
    max_designs: int = 2,
    designs: Sequence[Design] | None = None,
    max_leg_m: float = DEFAULT_MAX_LEG_M,
    floor_m: float | None = None,
    min_trials_per_design: int = DEFAULT_MIN_TRIALS_PER_DESIGN,
    upper_m: float = 20000.0,
    tolerance: float = 0.02,
) -> Plan:
    """The plan meeting every target (those given, the others by default)
    with the fewest metres (bisection on the budget to a relative ``tolerance``).

    Raises:
        ParameterError: no targets, or even ``upper_m`` metres cannot meet them.
    """
    if not targets:
        raise ParameterError("minimum_budget needs at least one target")

    def plan(budget: float) -> Plan:
        return plan_experiment(
            prior,
            budget,
            max_trials=max_trials,
            description=description,
            targets=targets,
            max_designs=max_designs,
            designs=designs,
            max_leg_m=max_leg_m,
            floor_m=floor_m,
            min_trials_per_design=min_trials_per_design,
        )

    high = plan(upper_m)
    if not high.meets_targets:
        raise ParameterError(
            f"even {upper_m:g} m cannot meet the targets (criterion {high.criterion:.3g})"
        )
    low_m, high_m = 0.0, upper_m
    while high_m - low_m > tolerance * high_m:
        middle = 0.5 * (low_m + high_m)
        try:
            candidate = plan(middle)
        except ParameterError:
            low_m = middle
            continue
        if candidate.meets_targets:
            high, high_m = candidate, middle
        else:
            low_m = middle
    return high


def expected_standard_errors(
    designs: Sequence[tuple[Design, int]],
    prior: ErrorParameters,
    description: RobotDescription | None = None,
) -> FloatArray:
    """Cramer-Rao standard errors (4,) of a given plan (SI), with the same
    measurement model the planner uses."""
    model = measurement_model(description, prior)
    info = np.zeros((4, 4))
    for design, n in designs:
        info += n * _candidate(design, prior, model).info
    return standard_errors(info)


def _candidate(
    design: Design,
    prior: ErrorParameters,
    model: MeasurementModel,
    operator: OperatorTime | None = None,
) -> _Candidate:
    derivatives = moment_derivatives(design.path(), prior)
    if model is None:
        meas = np.zeros((3, 3))
    elif callable(model):
        meas = model(design)
    else:
        meas = np.asarray(model)
    seconds = operator.trial_seconds(design) if operator is not None else 0.0
    return _Candidate(design, trial_information(derivatives, meas), seconds)


def _batch_errors(info: FloatArray) -> tuple[FloatArray, npt.NDArray[np.bool_]]:
    """Standard errors (B, 4) of a batch of informations (B, 4, 4), and a mask
    of the well-conditioned ones."""
    scale = np.array(PARAMETER_SCALES)
    scaled = info * np.outer(scale, scale)
    eigen = np.linalg.eigvalsh(scaled)
    ok = eigen[:, 0] > eigen[:, -1] * 1e-12
    safe = np.where(ok[:, None, None], scaled, np.eye(4))
    inverse = np.linalg.inv(safe)
    errors: FloatArray = np.sqrt(np.abs(np.einsum("bii->bi", inverse))) * scale
    return errors, ok


def _groups(
    candidates: list[_Candidate], size: int, budget: _Budget, divisor: FloatArray
) -> list[tuple[_Candidate, ...]]:
    if size == 1:
        return [(c,) for c in candidates]
    pool = _pool(candidates, budget, divisor)
    return [g for g in itertools.combinations(pool, size) if budget.fits(g)]


def _pool(candidates: list[_Candidate], budget: _Budget, divisor: FloatArray) -> list[_Candidate]:
    """The designs worth mixing: best alone, and best per metre for each
    parameter's own information (the diagonal of the per-metre information
    after removing the other parameters, i.e. 1 / (I^-1)_aa per metre)."""
    n_alone = np.array([budget.most(c) for c in candidates])
    infos = np.array([c.info for c in candidates])
    errors, ok = _batch_errors(infos * np.maximum(n_alone, 1)[:, None, None])
    value = np.where(ok, criterion_value(errors, divisor), np.inf)
    chosen = set(np.argsort(value, kind="stable")[: _POOL_SIZE // 2].tolist())
    # marginal information per metre for each parameter alone (the others known)
    per_metre = (
        np.einsum("bii->bi", infos) / np.array([c.design.distance_m for c in candidates])[:, None]
    )
    per_trial = np.einsum("bii->bi", infos)
    for a in range(4):
        chosen.update(np.argsort(-per_metre[:, a], kind="stable")[:2].tolist())
        chosen.update(np.argsort(-per_trial[:, a], kind="stable")[:1].tolist())
    return [candidates[i] for i in sorted(chosen)]


def _count_grid(low: int, high: int) -> FloatArray:
    if high - low + 1 <= _GRID_STEPS:
        return np.arange(low, high + 1, dtype=np.float64)
    grid = np.unique(np.round(np.geomspace(low, high, _GRID_STEPS)))
    return grid.astype(np.float64)


def _allocate(
    group: Sequence[_Candidate], budget: _Budget, divisor: FloatArray
) -> tuple[float, tuple[PlanItem, ...], FloatArray] | None:
    """Best integer trial counts (each at least ``budget.min_n``) for a group
    of designs: the first designs' counts from a grid, the last takes what
    budget is left; then a local search of +-1 steps."""
    infos = np.array([c.info for c in group])
    head = range(len(group) - 1)
    grids = [_count_grid(budget.min_n, budget.most(group[i])) for i in head]
    counts = (
        np.array(list(itertools.product(*grids)), dtype=np.float64) if head else np.zeros((1, 0))
    )
    counts = _complete(counts, group, budget)
    if counts.size == 0:
        return None
    best_counts, best_value = _best(counts, infos, divisor)
    if best_counts is None:
        return None
    if head:
        # pattern search: +-step moves, the step halving from about the grid's
        # spacing down to 1, so the work grows with log(budget), not the budget
        largest = max(float(best_counts.max()), 1.0)
        step = 2.0 ** math.floor(math.log2(max(1.0, largest / _GRID_STEPS)))
        moves = [
            np.array(s, dtype=np.float64)
            for s in itertools.product((-1, 0, 1), repeat=len(head))
            if any(s)
        ]
        while step >= 1.0:
            for _ in range(_SEARCH_ROUNDS):
                around = np.array([best_counts[:-1] + step * s for s in moves])
                around = around[np.all(around >= budget.min_n, axis=1)]
                if around.size == 0:
                    break
                trial = _complete(around, group, budget)
                if trial.size == 0:
                    break
                counts_new, value_new = _best(trial, infos, divisor)
                if counts_new is None or value_new >= best_value - 1e-15:
                    break
                best_counts, best_value = counts_new, value_new
            step /= 2.0
    total = np.einsum("d,dij->ij", best_counts, infos)
    errors = standard_errors(total)
    items = tuple(
        PlanItem(c.design, int(n)) for c, n in zip(group, best_counts, strict=True) if n > 0
    )
    return best_value, items, errors


def _complete(head_counts: FloatArray, group: Sequence[_Candidate], budget: _Budget) -> FloatArray:
    """Append the last design's count: as many trials as the budget (metres,
    trials, seconds) leaves; rows where it would be below ``budget.min_n``
    are dropped."""
    lengths = np.array([c.design.distance_m for c in group])
    seconds = np.array([c.seconds for c in group])
    used_m = head_counts @ lengths[:-1]
    used_n = head_counts.sum(axis=1)
    used_s = head_counts @ seconds[:-1]
    last = np.minimum(
        np.floor((budget.metres - used_m) / lengths[-1] + 1e-9), budget.trials - used_n
    )
    if math.isfinite(budget.seconds) and seconds[-1] > 0:
        last = np.minimum(last, np.floor((budget.seconds - used_s) / seconds[-1] + 1e-9))
    last = np.minimum(last, 10**9)
    keep = last >= budget.min_n
    return np.column_stack([head_counts[keep], last[keep]])


def _best(
    counts: FloatArray, infos: FloatArray, divisor: FloatArray
) -> tuple[FloatArray | None, float]:
    total = np.einsum("bd,dij->bij", counts, infos)
    errors, ok = _batch_errors(total)
    values = np.where(ok, criterion_value(errors, divisor), np.inf)
    index = int(np.argmin(values))
    if not np.isfinite(values[index]):
        return None, math.inf
    return counts[index], float(values[index])
