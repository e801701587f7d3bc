"""The best plan of general paths within an operator time.

:func:`best_plan` searches mixtures of shapes within an operator time
(odohil/science/path_plans.py :func:`~odohil.science.path_plans.path_seconds`:
marking and measuring, driving, spinning) for the one that estimates the most
parameters the shapes can identify, and among those the smallest largest
ratio of standard error to target (:func:`default_targets`). The scores are
odohil/science/path_plans.py's.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from odohil.errors import ParameterError
from odohil.science import targets
from odohil.science.path_plans import (
    SINGULAR,
    PlanScore,
    RobotModel,
    Shape,
    acting,
    identify,
    path_informations,
    path_seconds,
    score_plan,
    shape_path,
)
from odohil.science.paths import Design, FloatArray
from odohil.science.planner import DEFAULT_MIN_TRIALS_PER_DESIGN, OperatorTime

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
