"""Coverage of the 95 % intervals below the planner's minimum trials a design.

Issue 18/19 follow-up (stop 25): ``odohil run --plan k=1,l=1,n=3
--allow-few-trials`` on the fake Nomad (seed 2) ended "trusted" with E_T
-0.78 [-1.035, -0.531] against the fake's -0.02. This measures, on the
discrete model alone (no driver), how often each 95 % interval misses the
truth for n trials of one design, and how many fits the verdict trusts with a
miss: the reason a design below the planner's minimum
(odohil/science/planner.py DEFAULT_MIN_TRIALS_PER_DESIGN) makes the verdict
doubtful (odohil/science/estimators/verdict.py ``few_trial_designs``).

Usage: ``python bench/few_trials_coverage.py --n 2,3,5,10 --reps 200``
"""

from __future__ import annotations

import argparse
import math
import os
import time

import numpy as np

from odohil.errors import OdohilError
from odohil.science.estimators import Observation, estimate
from odohil.science.parameters import NOMAD150, PARAMETER_NAMES
from odohil.science.paths import Design
from odohil.science.simulator import simulate

MEASUREMENT = np.diag([1e-6, 1e-6, 4e-6])
"""A tape-like measurement: 1 mm in x and y, 2 mrad in heading."""


def one_n(n: int, reps: int, design: Design, seed: int) -> str:
    rng = np.random.default_rng(seed)
    truth = dict(zip(PARAMETER_NAMES, NOMAD150.as_tuple(), strict=True))
    misses = dict.fromkeys(PARAMETER_NAMES, 0)
    fits = trusted = trusted_miss = 0
    for _ in range(reps):
        poses = simulate(design.path(), NOMAD150, n, seed=rng, segment_m=0.01).pose_change
        poses = poses + rng.multivariate_normal(np.zeros(3), MEASUREMENT, size=n)
        try:
            result = estimate([Observation(design, p, MEASUREMENT) for p in poses])
        except OdohilError:  # a fit that cannot be made is counted out
            continue
        fits += 1
        missed = [p.name for p in result.parameters if not p.ci95[0] <= truth[p.name] <= p.ci95[1]]
        for name in missed:
            misses[name] += 1
        trusted += result.verdict.trusted
        trusted_miss += result.verdict.trusted and bool(missed)
    se = math.sqrt(0.05 * 0.95 / max(fits, 1))
    rates = ", ".join(f"{k} {v / max(fits, 1):.1%}" for k, v in misses.items())
    return f"| {n} | {fits} | {rates} | {trusted} | {trusted_miss} | {se:.1%} |"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", default="2,3,5,10")
    parser.add_argument("--reps", type=int, default=200)
    parser.add_argument("--seed", type=int, default=7)
    args = parser.parse_args()
    design = Design(1, 1.0, "turn")
    load = os.getloadavg()
    started = time.monotonic()
    print(f"{design.label()} at the Nomad's values, {args.reps} sessions each, seed {args.seed}")
    print(
        "| trials | fits | 95 % interval misses the truth | trusted | trusted with a miss "
        "| SE of a 5 % rate |"
    )
    print("|---|---|---|---|---|---|")
    for n in (int(v) for v in args.n.split(",")):
        print(one_n(n, args.reps, design, args.seed), flush=True)
    print(f"\nload average before: {load[0]:.1f}; wall {time.monotonic() - started:.0f} s")


if __name__ == "__main__":
    main()
