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

Criterion (smaller is better), from the expected standard errors se_a:

- with targets (any subset of E_R, E_T, K_theta, K_rho, SI standard errors):
  max_a se_a / target_a, so a value <= 1 meets every target;
- without targets: sum_a (se_a / r_a)^2, the sum of relative variances, with
  r_a = max(|prior_a|, scale_a) and scales 1e-3 rad/m, 1e-2, 1e-6 rad^2/m,
  1e-5 m (E_R, E_T, K_theta, K_rho), so a parameter guessed near zero is
  judged against a typical magnitude instead.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

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
from odohil.science.paths import VARIANTS, Design, FloatArray, floor_choreography
from odohil.science.robot_description import RobotDescription

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
_POOL_SIZE = 24
_GRID_STEPS = 24
"""Trial counts tried per design in a mixture (before the last design takes
what is left of the budget)."""
_SEARCH_ROUNDS = 64
"""Most moves of the local search at one step size."""


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
    """A recommended experiment.

    Attributes:
        items: designs and their trial counts.
        standard_errors: (4,) expected standard errors (Cramer-Rao, SI) of
            E_R rad/m, E_T, K_theta rad^2/m, K_rho m.
        criterion: the criterion value (see module docs); <= 1 meets all targets
            when targets were given.
        targets: the targets used (SI), by parameter name; empty if none.
    """

    items: tuple[PlanItem, ...]
    standard_errors: FloatArray
    criterion: float
    targets: Mapping[str, float]

    @property
    def distance_m(self) -> float:
        """Total metres driven."""
        return sum(item.distance_m for item in self.items)

    @property
    def n_trials(self) -> int:
        """Total number of trials (each marked and measured)."""
        return sum(item.n_trials for item in self.items)

    @property
    def meets_targets(self) -> bool:
        """True when targets were given and every one is met."""
        return bool(self.targets) and self.criterion <= 1.0

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


def measurement_model(
    description: RobotDescription | None, prior: ErrorParameters
) -> MeasurementModel:
    """The Fisher measurement model for a robot description (None: exact poses)."""
    if description is None:
        return None
    return pose_spread_measurement(description, prior)


def check_targets(targets: Mapping[str, float] | None) -> dict[str, float]:
    """Validated targets: names among E_R, E_T, K_theta, K_rho; positive SI values."""
    checked: dict[str, float] = {}
    for name, value in (targets or {}).items():
        if name not in PARAMETER_NAMES:
            raise ParameterError(f"unknown target {name!r}; choose from {PARAMETER_NAMES}")
        if not math.isfinite(value) or value <= 0:
            raise ParameterError(f"target for {name} must be a positive number, got {value!r}")
        checked[name] = float(value)
    return checked


def criterion_weights(
    prior: ErrorParameters, targets: Mapping[str, float]
) -> tuple[FloatArray, bool]:
    """Per-parameter divisors of the standard errors, and whether the criterion
    is the maximum (targets) or the sum of squares (no targets)."""
    if targets:
        divisor = np.array([targets.get(name, math.inf) for name in PARAMETER_NAMES])
        return divisor, True
    magnitudes = np.abs(np.array(prior.as_tuple()))
    return np.maximum(magnitudes, np.array(PARAMETER_SCALES)), False


def criterion_value(errors: FloatArray, divisor: FloatArray, use_max: bool) -> FloatArray | float:
    """The criterion of standard errors (..., 4); see the module docs."""
    ratios = errors / divisor
    if use_max:
        return np.max(ratios, axis=-1)  # type: ignore[no-any-return]
    return np.sum(ratios**2, axis=-1)  # type: ignore[no-any-return]


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
) -> Plan:
    """Recommend designs and trial counts within a budget.

    Args:
        prior: guessed parameter values (SI); the information is evaluated there.
        budget_m: most metres driven in all.
        max_trials: most trials in all (each must be marked and measured).
        description: floor-mark measurement (None: exact pose changes).
        targets: wanted standard errors (SI) by parameter name; see module docs.
        max_designs: mixtures of at most this many designs (1 to 3).
        designs: the candidate designs (default: :func:`design_grid`).
        max_leg_m: longest leg allowed, metres (for the default grid).
        floor_m: free floor, metres: no plan covers more (see
            :attr:`Plan.excursion_m`). None: :data:`DEFAULT_FLOOR_M` for the
            default grid, no limit for given ``designs``.

    Raises:
        ParameterError: bad budget, no design fits it, or bad targets.
    """
    if floor_m is not None and (not math.isfinite(floor_m) or floor_m <= 0):
        raise ParameterError(f"the floor must be a positive number of metres, got {floor_m!r}")
    floor = floor_m if floor_m is not None else (DEFAULT_FLOOR_M if designs is None else math.inf)
    if not math.isfinite(budget_m) or budget_m <= 0:
        raise ParameterError(f"the budget must be a positive number of metres, got {budget_m!r}")
    if max_trials is not None and max_trials < 1:
        raise ParameterError(f"max_trials must be at least 1, got {max_trials}")
    if not 1 <= max_designs <= MAX_DESIGNS:
        raise ParameterError(f"max_designs must be 1 to {MAX_DESIGNS}, got {max_designs}")
    checked = check_targets(targets)
    pool = list(designs) if designs is not None else design_grid(max_leg_m=max_leg_m)
    pool = [d for d in pool if d.distance_m <= budget_m and d.l_m <= floor]
    if not pool:
        raise ParameterError(
            f"no candidate design fits in a budget of {budget_m:g} m and {floor:g} m of floor"
        )
    trial_cap = max_trials if max_trials is not None else 10**6
    model = measurement_model(description, prior)
    candidates = [_candidate(design, prior, model) for design in pool]
    divisor, use_max = criterion_weights(prior, checked)

    best: tuple[float, tuple[PlanItem, ...], FloatArray] | None = None
    for size in range(1, max_designs + 1):
        for group in _groups(candidates, size, budget_m, trial_cap, divisor, use_max):
            result = _allocate(group, budget_m, trial_cap, divisor, use_max)
            if result is None or (best is not None and result[0] >= best[0]):
                continue
            if floor_choreography([(i.design, i.n_trials) for i in result[1]]).excursion_m > floor:
                continue
            best = result
    if best is None:
        raise ParameterError("no plan within the budget identifies all four parameters")
    value, items, errors = best
    return Plan(items=items, standard_errors=errors, criterion=float(value), targets=checked)


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
    upper_m: float = 20000.0,
    tolerance: float = 0.02,
) -> Plan:
    """The plan meeting every target with the fewest metres (bisection on the
    budget to a relative ``tolerance``).

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


def _candidate(design: Design, prior: ErrorParameters, model: MeasurementModel) -> _Candidate:
    derivatives = moment_derivatives(design.path(), prior)
    if model is None:
        meas = np.zeros((3, 3))
    elif callable(model):
        meas = model(design)
    else:
        meas = np.asarray(model)
    return _Candidate(design, trial_information(derivatives, meas))


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
    candidates: list[_Candidate],
    size: int,
    budget_m: float,
    trial_cap: int,
    divisor: FloatArray,
    use_max: bool,
) -> list[tuple[_Candidate, ...]]:
    if size == 1:
        return [(c,) for c in candidates]
    pool = _pool(candidates, budget_m, trial_cap, divisor, use_max)
    return [g for g in itertools.combinations(pool, size) if _fits(g, budget_m, trial_cap)]


def _fits(group: Sequence[_Candidate], budget_m: float, trial_cap: int) -> bool:
    return len(group) <= trial_cap and sum(c.design.distance_m for c in group) <= budget_m


def _pool(
    candidates: list[_Candidate],
    budget_m: float,
    trial_cap: int,
    divisor: FloatArray,
    use_max: bool,
) -> list[_Candidate]:
    """The designs worth mixing: best alone, and best per metre for each
    parameter's own information (the diagonal of the per-metre information
    after removing the other parameters, i.e. 1 / (I^-1)_aa per metre)."""
    n_alone = np.array([_max_trials(c.design, budget_m, trial_cap) for c in candidates])
    infos = np.array([c.info for c in candidates])
    errors, ok = _batch_errors(infos * np.maximum(n_alone, 1)[:, None, None])
    value = np.where(ok, criterion_value(errors, divisor, use_max), np.inf)
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


def _max_trials(design: Design, budget_m: float, trial_cap: int) -> int:
    return min(trial_cap, math.floor(budget_m / design.distance_m + 1e-9))


def _count_grid(high: int) -> FloatArray:
    if high <= _GRID_STEPS:
        return np.arange(1, high + 1, dtype=np.float64)
    grid = np.unique(np.round(np.geomspace(1, high, _GRID_STEPS)))
    return grid.astype(np.float64)


def _allocate(
    group: Sequence[_Candidate],
    budget_m: float,
    trial_cap: int,
    divisor: FloatArray,
    use_max: bool,
) -> tuple[float, tuple[PlanItem, ...], FloatArray] | None:
    """Best integer trial counts (each at least 1) for a group of designs: the
    first designs' counts from a grid, the last takes what budget is left;
    then a local search of +-1 steps."""
    lengths = np.array([c.design.distance_m for c in group])
    infos = np.array([c.info for c in group])
    head = range(len(group) - 1)
    grids = [_count_grid(_max_trials(group[i].design, budget_m, trial_cap)) for i in head]
    counts = (
        np.array(list(itertools.product(*grids)), dtype=np.float64) if head else np.zeros((1, 0))
    )
    counts = _complete(counts, lengths, budget_m, trial_cap)
    if counts.size == 0:
        return None
    best_counts, best_value = _best(counts, infos, divisor, use_max)
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
                around = around[np.all(around >= 1, axis=1)]
                if around.size == 0:
                    break
                trial = _complete(around, lengths, budget_m, trial_cap)
                if trial.size == 0:
                    break
                counts_new, value_new = _best(trial, infos, divisor, use_max)
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


def _complete(
    head_counts: FloatArray, lengths: FloatArray, budget_m: float, trial_cap: int
) -> FloatArray:
    """Append the last design's count: as many trials as the budget leaves
    (rows where it would be below 1 are dropped)."""
    used_m = head_counts @ lengths[:-1]
    used_n = head_counts.sum(axis=1)
    last = np.minimum(np.floor((budget_m - used_m) / lengths[-1] + 1e-9), trial_cap - used_n)
    keep = last >= 1
    return np.column_stack([head_counts[keep], last[keep]])


def _best(
    counts: FloatArray, infos: FloatArray, divisor: FloatArray, use_max: bool
) -> tuple[FloatArray | None, float]:
    total = np.einsum("bd,dij->bij", counts, infos)
    errors, ok = _batch_errors(total)
    values = np.where(ok, criterion_value(errors, divisor, use_max), np.inf)
    index = int(np.argmin(values))
    if not np.isfinite(values[index]):
        return None, math.inf
    return counts[index], float(values[index])
