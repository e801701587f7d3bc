"""Below the planner's minimum trials a design the verdict is doubtful
(odohil/science/estimators/verdict.py ``few_trial_designs``).

Found at stop 25: ``odohil run --plan k=1,l=1,n=3 --allow-few-trials`` on the
fake Nomad (seed 2) ended "trusted" with E_T -0.78 [-1.035, -0.531] against
the fake's -0.02. On the discrete model alone, E_T's 95 % interval from 3
trials of that design missed the truth in 12 % of 200 sessions
(bench/few_trials_coverage.py, BENCHMARKS.md): the intervals are not honest
there, so the verdict may not say trusted.
"""

from __future__ import annotations

import numpy as np

from odohil.science.estimators import Observation, estimate
from odohil.science.estimators.paths import estimate_paths
from odohil.science.parameters import NOMAD150
from odohil.science.path_trials import PathTrial
from odohil.science.paths import Design, square
from odohil.science.planner import DEFAULT_MIN_TRIALS_PER_DESIGN
from odohil.science.simulator import simulate

MEASUREMENT = np.diag([1e-6, 1e-6, 4e-6])
DESIGNS = (Design(1, 1.0, "turn"), Design(4, 0.5, "turn"))


def _observations(counts: tuple[int, ...], seed: int) -> list[Observation]:
    rng = np.random.default_rng(seed)
    out = []
    for design, n in zip(DESIGNS, counts, strict=True):
        poses = simulate(design.path(), NOMAD150, n, seed=rng, segment_m=0.01).pose_change
        poses = poses + rng.multivariate_normal(np.zeros(3), MEASUREMENT, size=n)
        out += [Observation(design, p, MEASUREMENT) for p in poses]
    return out


def test_a_design_below_the_minimum_makes_the_verdict_doubtful_and_names_it() -> None:
    result = estimate(_observations((3, DEFAULT_MIN_TRIALS_PER_DESIGN), seed=2))
    assert result.verdict.status == "doubtful", result.verdict
    reason = next(r for r in result.verdict.reasons if r.startswith("fewer than"))
    assert reason == (
        f"fewer than {DEFAULT_MIN_TRIALS_PER_DESIGN} trials a design, the planner's minimum "
        "for honest intervals: k=1 l=1 m turn (3)"
    )


def test_the_minimum_itself_is_enough() -> None:
    n = DEFAULT_MIN_TRIALS_PER_DESIGN
    result = estimate(_observations((n, n), seed=2))
    assert not any(r.startswith("fewer than") for r in result.verdict.reasons), result.verdict
    assert result.verdict.status == "trusted", result.verdict


def _path_trials(counts: tuple[int, int], seed: int) -> list[PathTrial]:
    """Trials of two general paths (a 1 m square clockwise, a 2 m straight
    run), ``counts`` of each, measured like a tape."""
    rng = np.random.default_rng(seed)
    out = []
    for (path, family, direction), n in zip(
        ((square(1.0, counter_clockwise=False), "square", "cw"),
         (Design(0.5, 2.0, "reverse").path(), "straight", "forward")),
        counts, strict=True,
    ):  # fmt: skip
        poses = simulate(path, NOMAD150, n, seed=rng, segment_m=0.01).pose_change
        poses = poses + rng.multivariate_normal(np.zeros(3), MEASUREMENT, size=n)
        out += [PathTrial(path, p, MEASUREMENT, family=family, direction=direction) for p in poses]
    return out


def test_a_general_path_below_the_minimum_makes_the_verdict_doubtful_too() -> None:
    """The general-path estimator (odohil/science/estimators/paths.py) judges
    by the same rule: a path family of 3 trials cannot be trusted (issue 31)."""
    n = DEFAULT_MIN_TRIALS_PER_DESIGN
    few = estimate_paths(_path_trials((3, n), seed=2), turns_exact=True)
    assert few.verdict.status == "doubtful", few.verdict
    reason = next(r for r in few.verdict.reasons if r.startswith("fewer than"))
    assert reason == (
        f"fewer than {n} trials a path family and direction, the planner's minimum for "
        "honest intervals: square cw (3)"
    )
    enough = estimate_paths(_path_trials((n, n), seed=2), turns_exact=True)
    assert not any(r.startswith("fewer than") for r in enough.verdict.reasons), enough.verdict
