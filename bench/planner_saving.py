"""Benchmark: how many metres the planner saves for the paper's reported precision.

Usage: ``python bench/planner_saving.py [--experiments 300] [--workers 2] [--max-trials 60]``

Targets (the paper's reported standard errors): E_R 0.004 deg/m, K_theta
0.003 deg^2/m, 1+E_T 0.04, K_rho 1.9e-5 m. Measurement: 1 mm tape sigma,
screws on a 0.2 m radius circle, one cross distance. The paper drove 960 m
(30 x 12 m + 30 x 20 m). The planner's cheapest plan meeting every target
(odohil.science.planner.minimum_budget, at most ``--max-trials`` trials,
mixtures of up to 2 designs) is then simulated ``--experiments`` times
through the full floor-marks path (bench/efficiency.py's run_chunk) and
fitted by the joint estimator; its RMSE is compared with the targets.
"""

from __future__ import annotations

import argparse
import math
import multiprocessing
import os
import sys
import time

import numpy as np
from efficiency import Outcome, run_chunk, summarise

from odohil.science.fisher import default_description
from odohil.science.parameters import NOMAD150, PAPER_UNITS, PARAMETER_NAMES
from odohil.science.paths import Design
from odohil.science.planner import Plan, expected_standard_errors, minimum_budget
from odohil.units import parameter_to_paper as to_paper

TARGETS = {
    "E_R": math.radians(0.004),
    "E_T": 0.04,
    "K_theta": 0.003 * (math.pi / 180.0) ** 2,
    "K_rho": 1.9e-5,
}
PAPER_PLAN = [(Design(1, 6.0), 30), (Design(20, 0.5), 30)]
PAPER_METRES = sum(d.distance_m * n for d, n in PAPER_PLAN)
CHUNK = 10

_plan: list[tuple[Design, int]] = []


def _init(plan: list[tuple[Design, int]]) -> None:
    _plan[:] = plan


def _chunk(args: tuple[int, int]) -> list[Outcome]:
    n, seed = args
    return run_chunk(_plan, NOMAD150, default_description(0.001), n, seed, methods=("joint",))


def describe(plan: Plan) -> str:
    """One line per design and the expected errors against the targets."""
    lines = [
        f"  {item.design.label():>22}  x {item.n_trials:>3}  = {item.distance_m:g} m"
        for item in plan.items
    ]
    lines.append(f"  total {plan.distance_m:g} m in {plan.n_trials} trials")
    for a, name in enumerate(PARAMETER_NAMES):
        se = float(plan.standard_errors[a])
        lines.append(
            f"  expected stderr {name:>7}: {to_paper(name, se):.3g} {PAPER_UNITS[name]}"
            f" (target {to_paper(name, TARGETS[name]):.3g}, ratio {se / TARGETS[name]:.2f})"
        )
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--experiments", type=int, default=300)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--max-trials", type=int, default=60)
    parser.add_argument("--seed", type=int, default=7)
    args = parser.parse_args()
    description = default_description(0.001)
    print(f"load average before: {os.getloadavg()[0]:.2f}", flush=True)

    reference = expected_standard_errors(PAPER_PLAN, NOMAD150, description)
    print(f"paper's plan: {PAPER_METRES:g} m, 60 trials; expected stderr / target:")
    for a, name in enumerate(PARAMETER_NAMES):
        print(f"  {name:>7}: {float(reference[a]) / TARGETS[name]:.2f}")

    start = time.perf_counter()
    plan = minimum_budget(NOMAD150, TARGETS, max_trials=args.max_trials, description=description)
    print(f"planner (at most {args.max_trials} trials), {time.perf_counter() - start:.0f} s:")
    print(describe(plan))
    print(
        f"saving: {PAPER_METRES - plan.distance_m:g} m "
        f"({100 * (1 - plan.distance_m / PAPER_METRES):.0f} % of {PAPER_METRES:g} m)",
        flush=True,
    )

    seeds = np.random.SeedSequence(args.seed).generate_state(args.experiments // CHUNK + 1)
    jobs, left = [], args.experiments
    for seed in seeds:
        if left <= 0:
            break
        jobs.append((min(CHUNK, left), int(seed)))
        left -= CHUNK
    start = time.perf_counter()
    outcomes: list[Outcome] = []
    with multiprocessing.Pool(args.workers, initializer=_init, initargs=(plan.designs(),)) as pool:
        for chunk in pool.imap_unordered(_chunk, jobs):
            outcomes.extend(chunk)
            print(f"{len(outcomes)}/{args.experiments}", file=sys.stderr, flush=True)
    rmse, rmse_se, coverage, n_ok = summarise(outcomes, NOMAD150, "joint")
    print(f"simulated {len(outcomes)} experiments of the plan ({n_ok} joint estimates):")
    for a, name in enumerate(PARAMETER_NAMES):
        print(
            f"  {name:>7}: RMSE {to_paper(name, float(rmse[a])):.3g} +- "
            f"{to_paper(name, float(rmse_se[a])):.2g} {PAPER_UNITS[name]}, "
            f"RMSE/target {rmse[a] / TARGETS[name]:.2f}, 95% coverage {coverage[a]:.3f}"
        )
    unclear = sum(o.unclear_trials for o in outcomes)
    rejected = sum(o.rejected_trials for o in outcomes)
    print(f"trials not clear-cut {unclear}, rejected {rejected}")
    print(
        f"wall clock {time.perf_counter() - start:.0f} s, load average after: "
        f"{os.getloadavg()[0]:.2f}"
    )


if __name__ == "__main__":
    main()
