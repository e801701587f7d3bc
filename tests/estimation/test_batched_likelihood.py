"""The profile intervals' batched likelihood is the one-point likelihood, bit
for bit (odohil/science/estimators/intervals.py, issue 18's speed work).

The profile's re-fit evaluates a step's halvings and the numeric gradient's
points in one batch (``MomentModel.moments`` and
``likelihood.nll_many``). Its decisions compare NLLs to 1e-9 and difference
them over steps of 1e-4 standard errors, so the batch must give exactly the
numbers :func:`evaluate` gives one point at a time; then the intervals are
those of the point-by-point search. Both models: the forth-and-back designs,
and general paths with turn errors and K_spin (whose batched matrix products
would round differently).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import pytest

from odohil.science.estimators import Observation
from odohil.science.estimators.joint import designs_of
from odohil.science.estimators.likelihood import (
    DESIGN_MODEL,
    GroupStats,
    MomentModel,
    StackedGroups,
    evaluate,
    nll_many,
    to_phi,
    with_moments,
)
from odohil.science.estimators.observations import group_trials
from odohil.science.estimators.paths import PathModel, path_groups, turn_model
from odohil.science.moments import PathSet, TurnErrors, pose_moments
from odohil.science.parameters import NOMAD150
from odohil.science.path_trials import PathTrial
from odohil.science.paths import Design, EncoderPath, Leg, Step, Turn

MEAS = np.diag([1e-6, 1e-6, math.radians(0.3) ** 2])
TURNS = TurnErrors(-0.007, -0.007, -0.012, -0.012, k_spin=1e-4)


def _design_case() -> tuple[list[GroupStats], MomentModel]:
    rng = np.random.default_rng(3)
    observations = []
    for design, n in ((Design(1, 6.0), 8), (Design(20, 0.5), 8), (Design(0.5, 2.0), 5)):
        m = pose_moments(design.path(), NOMAD150)
        draws = rng.multivariate_normal(m.mean, m.cov + MEAS, size=n)
        observations += [Observation(design, v, MEAS) for v in draws]
    return list(group_trials(observations)), DESIGN_MODEL


def _path(rng: np.random.Generator) -> EncoderPath:
    steps: list[Step] = []
    for _ in range(6):
        steps.append(Leg(float(rng.uniform(0.1, 0.5))))
        kind = "spin" if rng.random() < 0.5 else "arc"
        steps.append(Turn(float(rng.uniform(-1.5, 1.5)), kind))
    return EncoderPath(tuple(steps), name="random")


def _path_case() -> tuple[list[GroupStats], MomentModel]:
    rng = np.random.default_rng(4)
    trials = []
    for i in range(12):
        path = _path(rng)
        m = pose_moments(path, NOMAD150, TURNS)
        v = rng.multivariate_normal(m.mean, m.cov + MEAS)
        trials.append(PathTrial(path, v, MEAS, trial=i + 1))
    paths = [t.path for t in trials]
    model = PathModel(PathSet.of(tuple(paths)), turn_model(paths, split_directions=False))
    return path_groups(trials), model


@pytest.mark.parametrize("case", [_design_case, _path_case], ids=["designs", "paths"])
def test_a_batch_of_points_has_the_nll_of_each_point(
    case: Callable[[], tuple[list[GroupStats], MomentModel]],
) -> None:
    groups, model = case()
    layout = model.layout
    keys = designs_of(groups)
    rng = np.random.default_rng(5)
    centre = np.zeros(layout.size)
    centre[:4] = to_phi(NOMAD150)
    if layout.size > 4:
        centre[4:] = [*([-0.01] * (layout.size - 5)), math.log(TURNS.k_spin)]
    anchor = model.point(centre, keys, derivatives=True)
    scale = np.full(layout.size, 1e-3)
    scale[list(layout.log_rates)] = 0.3
    stack = StackedGroups.of(groups)
    assert anchor.d_means is not None
    d_mu = np.array([anchor.d_means[k] for k in stack.keys])
    for size in (2, 3, 4, 5, 8) * 4:
        phis = centre + rng.normal(size=(size, layout.size)) * scale
        means, covs = model.moments(phis, keys)
        mu, cov = stack.model_arrays(means, covs)
        batched = nll_many(stack, mu, cov, np.repeat(d_mu[None], size, axis=0), layout, True)
        for q, phi in enumerate(phis):
            one = model.point(phi, keys, derivatives=False)
            for j, key in enumerate(keys):
                assert np.array_equal(means[q, j], one.means[key])
                assert np.array_equal(covs[q, j], one.covs[key])
            value = evaluate(groups, with_moments(anchor, one), cox_reid=True)
            assert math.isfinite(value.nll)
            assert batched[q] == value.nll  # exactly: the same operations
