"""Benchmark: the planner's expected standard errors of general-path plans
against the spread of maximum-likelihood estimates (issue 19, deliverable 3).

Usage: ``python bench/path_plans_mc.py [--sets 400] [--workers 2] [--seed S]``

For each plan, ``--sets`` data sets are simulated with the discrete model with
turn errors (odohil/science/diff_drive.py simulate_turn_errors) plus
motion-capture noise (0.5 mm on x and y, 0.5 mrad on the heading) and fitted
by odohil/science/estimators/paths.py fit_paths (the Gaussian Cox-Reid ML fit
of ``odohil estimate``, turns_exact=False). Truth: E_R -0.35 deg/m, E_T -1.5 %,
K_theta 0.1 deg^2/m, K_rho 1e-4 m, e_turn 1.2 % on every turn, K_spin 2e-4
rad^2/rad. The expected standard errors are odohil/science/path_plans.py
score_plan's (Cramer-Rao, the same measurement covariance). Reports per
parameter the expected SE, the spread (SD) of the estimates, their ratio with
its Monte Carlo SE (from the estimates' 4th moments), and the bias in MC SEs;
paper units (E_R deg/m, K_theta deg^2/m, K_spin deg^2/deg; E_T and e_turn as
numbers, K_rho m).
tests/estimation/test_path_plans.py runs the first plan with 80 data sets.
"""

from __future__ import annotations

import argparse
import math
import multiprocessing
import os
import time

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402

from odohil import units  # noqa: E402
from odohil.science.diff_drive import simulate_turn_errors  # noqa: E402
from odohil.science.estimators.paths import fit_paths  # noqa: E402
from odohil.science.moments import TurnErrors  # noqa: E402
from odohil.science.parameters import ErrorParameters  # noqa: E402
from odohil.science.path_plans import RobotModel, Shape, score_plan, shape_path  # noqa: E402
from odohil.science.path_trials import PathTrial  # noqa: E402
from odohil.science.paths import Design, EncoderPath, Leg, Turn, square  # noqa: E402

TRUTH = ErrorParameters.from_paper_units(-0.35, -0.015, 0.1, 1e-4)
TURNS = TurnErrors.uniform(0.012, 2e-4)
MOCAP = np.diag([2.5e-7, 2.5e-7, 2.5e-7])


def arc_circle(radius_m: float, n_legs: int, ccw: bool) -> EncoderPath:
    """A circle cut into short legs, its heading changes arc turns."""
    angle = 2 * math.pi / n_legs * (1 if ccw else -1)
    chord = 2 * radius_m * math.sin(abs(angle) / 2)
    steps: list[Leg | Turn] = [Turn(angle / 2, "arc")]
    for i in range(n_legs):
        steps += [Leg(chord), Turn(angle if i < n_legs - 1 else angle / 2, "arc")]
    return EncoderPath(tuple(steps), name=f"arc circle {'ccw' if ccw else 'cw'}")


PLANS: dict[str, tuple[list[tuple[Shape, int]], bool]] = {
    "squares both ways, arc circles both ways, one-way runs (10 each)": (
        [
            (square(1.0, True), 10),
            (square(1.0, False), 10),
            (Design(0.5, 2.0, "reverse"), 10),
            (arc_circle(0.5, 12, True), 10),
            (arc_circle(0.5, 12, False), 10),
        ],
        False,
    ),
    "forth-and-back: one-way runs and turn designs (15 each)": (
        [(Design(0.5, 2.0, "reverse"), 15), (Design(2, 1.0, "turn"), 15)],
        False,
    ),
    "squares both ways and one-way runs (10 each), e_turn per direction": (
        [(square(1.0, True), 10), (square(1.0, False), 10), (Design(0.5, 2.0, "reverse"), 10)],
        True,
    ),
}


def one_set(job: tuple[str, int]) -> list[float]:
    name, seed = job
    plan, split = PLANS[name]
    rng = np.random.default_rng(seed)
    trials = []
    for shape, n in plan:
        path = shape_path(shape)
        poses = simulate_turn_errors(path, TRUTH, TURNS, n, seed=rng).pose_change
        poses += rng.multivariate_normal(np.zeros(3), MOCAP, n)
        trials += [PathTrial(path, pose, MOCAP) for pose in poses]
    fit = fit_paths(trials, turns_exact=False, split_directions=split)
    return [float(v) for v in fit.values]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sets", type=int, default=400)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--seed", type=int, default=20261127)
    args = parser.parse_args()
    start = time.perf_counter()
    for index, (name, (plan, split)) in enumerate(PLANS.items()):
        model = RobotModel(
            TRUTH, turns_exact=False, turns=TURNS, split_directions=split, measurement_cov=MOCAP
        )
        expected = score_plan(plan, model)
        jobs = [(name, args.seed + 100_000 * index + k) for k in range(args.sets)]
        with multiprocessing.Pool(args.workers) as pool:
            values = np.array(pool.map(one_set, jobs))
        live = [k for k, p in enumerate(expected.parameters) if p.estimable]
        truth = model.values()[live]
        se = expected.standard_errors[live]
        spread = values.std(axis=0, ddof=1)
        fourth = ((values - values.mean(axis=0)) ** 4).mean(axis=0)
        mc_se = np.sqrt((fourth - spread**4) / args.sets) / (2 * spread**2)
        bias = (values.mean(axis=0) - truth) / (spread / math.sqrt(args.sets))
        print(f"\n### {name}: {args.sets} data sets")
        print(
            "\n| parameter | expected SE | SD of estimates | ratio | MC SE of ratio "
            "| bias (MC SE) |"
        )
        print("|---|---|---|---|---|---|")
        names = [expected.names[k] for k in live]
        for j, pname in enumerate(names):
            se_p = units.parameter_to_paper(pname, float(se[j]))
            sd_p = units.parameter_to_paper(pname, float(spread[j]))
            print(
                f"| {pname} | {se_p:.4g} | {sd_p:.4g} | {spread[j] / se[j]:.3f} | "
                f"{mc_se[j] * spread[j] / se[j]:.3f} | {bias[j]:+.2f} |"
            )
        idle = [p.name for p in expected.parameters if not p.estimable]
        if idle:
            print(f"\nnot estimable: {', '.join(idle)}")
    print(f"\nwhole run {time.perf_counter() - start:.0f} s wall, {args.workers} workers")


if __name__ == "__main__":
    main()
