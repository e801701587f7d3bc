"""Benchmark: efficiency of the joint estimator and the paper's method.

Usage: ``python bench/efficiency.py [--experiments 1000] [--workers 2] [--seed S]``

At least 1000 simulated experiments of the paper's plan (30 trials k=1 l=6 m
plus 30 trials k=20 l=0.5 m, Nomad 150 values, 1 mm tape sigma, screws on a
0.2 m radius circle at 0/120/240 deg with one cross distance A->B), each
through the full pose-from-floor-marks path described below. For each
parameter and method: RMSE over the Cramer-Rao bound (same measurement
model, odohil.science.fisher) and the coverage of the 95 % intervals.
(bench/planner_saving.py reuses :func:`run_chunk`.)

For every trial of a plan: simulate the true pose change (discrete model),
make the floor-mark distances with the forward model plus N(0, sigma^2)
noise, recover the pose with floor_marks.solve_marks (prior: the model's pose
moments at the planning values), and hand the recovered pose and its
covariance to the estimators.
"""

from __future__ import annotations

import argparse
import multiprocessing
import os
import sys
import time

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

from dataclasses import dataclass  # noqa: E402

import numpy as np  # noqa: E402

from odohil import units  # noqa: E402
from odohil.errors import MeasurementError  # noqa: E402
from odohil.science.estimators import Observation, estimate  # noqa: E402
from odohil.science.fisher import cramer_rao, default_description, pose_spread_measurement  # noqa: E402
from odohil.science.floor_marks import MarkDistances, marks_from_pose, solve_marks  # noqa: E402
from odohil.science.moments import pose_moments  # noqa: E402
from odohil.science.parameters import NOMAD150, PARAMETER_NAMES, ErrorParameters  # noqa: E402
from odohil.science.paths import Design  # noqa: E402
from odohil.science.robot_description import RobotDescription  # noqa: E402
from odohil.science.simulator import simulate  # noqa: E402


@dataclass(frozen=True)
class Outcome:
    """One experiment's estimates (SI, order E_R, E_T, K_theta, K_rho)."""

    values: dict[str, np.ndarray]  # method -> (4,)
    stderr: dict[str, np.ndarray]
    low: dict[str, np.ndarray]  # 95 % interval bounds
    high: dict[str, np.ndarray]
    failed: dict[str, str]  # method -> error message
    unclear_trials: int
    rejected_trials: int


def run_chunk(
    plan: list[tuple[Design, int]],
    truth: ErrorParameters,
    description: RobotDescription,
    n_experiments: int,
    seed: int,
    methods: tuple[str, ...] = ("joint", "paper"),
) -> list[Outcome]:
    """``n_experiments`` independent experiments of ``plan`` under ``truth``."""
    rng = np.random.default_rng(seed)
    poses = {
        design: simulate(design.path(), truth, n * n_experiments, seed=rng).pose_change.reshape(
            n_experiments, n, 3
        )
        for design, n in plan
    }
    priors = {design: pose_moments(design.path(), truth) for design, _ in plan}
    sigma = description.sigma_m
    outcomes = []
    for e in range(n_experiments):
        observations = []
        unclear = rejected = 0
        for design, _ in plan:
            odometry = design.path().encoder_end_pose()
            for pose in poses[design][e]:
                exact = marks_from_pose(description, pose).as_array()
                noisy = np.abs(exact + rng.normal(0.0, sigma, exact.size))
                marks = MarkDistances.of(description, noisy)
                try:
                    solution = solve_marks(description, marks, odometry, prior=priors[design])
                except MeasurementError:
                    rejected += 1
                    continue
                unclear += not solution.clear_cut
                observations.append(Observation(design, solution.pose_change, solution.cov))
        values, stderr, low, high, failed = {}, {}, {}, {}, {}
        for method in methods:
            try:
                result = estimate(observations, method=method)  # type: ignore[arg-type]
            except Exception as exc:  # a failed fit is a result of the benchmark
                failed[method] = f"{type(exc).__name__}: {exc}"
                continue
            values[method] = np.array([p.value for p in result.parameters])
            stderr[method] = np.array([p.stderr for p in result.parameters])
            low[method] = np.array([p.ci95[0] for p in result.parameters])
            high[method] = np.array([p.ci95[1] for p in result.parameters])
        outcomes.append(Outcome(values, stderr, low, high, failed, unclear, rejected))
    return outcomes


def summarise(
    outcomes: list[Outcome], truth: ErrorParameters, method: str
) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """RMSE (4,), its Monte Carlo standard error (4,), 95 % coverage (4,) and the
    number of experiments the method produced an estimate for."""
    true = np.array(truth.as_tuple())
    ok = [o for o in outcomes if method in o.values]
    values = np.array([o.values[method] for o in ok])
    errors = values - true
    rmse = np.sqrt((errors**2).mean(axis=0))
    rmse_se = (errors**2).std(axis=0, ddof=1) / np.sqrt(len(ok)) / (2 * rmse)
    low = np.array([o.low[method] for o in ok])
    high = np.array([o.high[method] for o in ok])
    coverage = ((low <= true) & (true <= high)).mean(axis=0)
    return rmse, rmse_se, coverage, len(ok)


PAPER_PLAN = [(Design(1, 6.0), 30), (Design(20, 0.5), 30)]
CHUNK = 10


def _chunk(args: tuple[int, int]) -> list[Outcome]:
    n, seed = args
    return run_chunk(PAPER_PLAN, NOMAD150, default_description(0.001), n, seed)


def report(
    outcomes: list[Outcome], truth: ErrorParameters, bound: np.ndarray, methods: tuple[str, ...]
) -> str:
    """The table: per parameter, RMSE/bound and coverage for each method."""
    lines = [
        f"{'parameter':>9}  {'CR bound (paper units)':>22}  "
        + "  ".join(f"{m + ' RMSE/bound':>20}  {m + ' 95% cov.':>15}" for m in methods)
    ]
    summaries = {m: summarise(outcomes, truth, m) for m in methods}
    for a, name in enumerate(PARAMETER_NAMES):
        row = f"{name:>9}  {units.parameter_to_paper(name, float(bound[a])):>22.4g}  "
        cells = []
        for m in methods:
            rmse, rmse_se, coverage, _ = summaries[m]
            cells.append(
                f"{rmse[a] / bound[a]:>11.3f} +- {rmse_se[a] / bound[a]:.3f}  {coverage[a]:>15.3f}"
            )
        lines.append(row + "  ".join(f"{c:>20}" for c in cells))
    counts = ", ".join(f"{m}: {summaries[m][3]} estimates" for m in methods)
    unclear = sum(o.unclear_trials for o in outcomes)
    rejected = sum(o.rejected_trials for o in outcomes)
    failures: dict[str, int] = {}
    for o in outcomes:
        for m in o.failed:
            failures[m] = failures.get(m, 0) + 1
    lines.append(
        f"{len(outcomes)} experiments ({counts}; failed fits {failures or 'none'}); "
        f"trials not clear-cut {unclear}, rejected as inconsistent {rejected} "
        f"of {len(outcomes) * sum(n for _, n in PAPER_PLAN)}"
    )
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--experiments", type=int, default=1000)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--seed", type=int, default=20240601)
    args = parser.parse_args()
    description = default_description(0.001)
    bound = cramer_rao(
        PAPER_PLAN, NOMAD150, pose_spread_measurement(description, NOMAD150, n_samples=4096)
    )
    seeds = np.random.SeedSequence(args.seed).generate_state(args.experiments // CHUNK + 1)
    jobs = []
    left = args.experiments
    for seed in seeds:
        if left <= 0:
            break
        jobs.append((min(CHUNK, left), int(seed)))
        left -= CHUNK
    print(f"load average before: {os.getloadavg()[0]:.2f}; {args.workers} workers", flush=True)
    start = time.perf_counter()
    outcomes: list[Outcome] = []
    with multiprocessing.Pool(args.workers) as pool:
        for chunk in pool.imap_unordered(_chunk, jobs):
            outcomes.extend(chunk)
            print(
                f"{len(outcomes)}/{args.experiments} experiments, "
                f"{time.perf_counter() - start:.0f} s",
                file=sys.stderr,
                flush=True,
            )
    elapsed = time.perf_counter() - start
    print(report(outcomes, NOMAD150, bound, ("joint", "paper")))
    print(
        f"wall clock {elapsed:.0f} s, load average after: {os.getloadavg()[0]:.2f}",
        flush=True,
    )


if __name__ == "__main__":
    main()
