"""Benchmark: 95 % coverage and bias of the estimates at small n, through the floor marks.

Usage: ``python bench/coverage.py [--replications 1000] [--n 5,10,20,30]
[--noise gauss,t3] [--method robust] [--workers 1] [--seed S]``

For each n (trials per design) and tape-noise law: replications of the
paper's plan (n trials k=1 l=6 m plus n trials k=20 l=0.5 m, Nomad 150
values, 1 mm tape sigma, the default screws with one cross distance), each
trial through the full floor-marks path of bench/efficiency.py (true pose
from the discrete model, distances from the forward model plus tape noise,
pose recovered by floor_marks.solve_marks with the model's prior). Tape
noise: ``gauss`` N(0, sigma^2), or ``t3`` Student-t with 3 degrees of
freedom scaled to the same SD (sigma / sqrt(3) times a t3 draw); the solver
and the estimator still assume sigma. Reports per parameter the 95 % interval
coverage with its Monte Carlo SE, the relative bias of the point estimate
with its MC SE, the verdict counts, and the failures.
"""

from __future__ import annotations

import argparse
import math
import multiprocessing
import os
import sys
import time

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

from dataclasses import dataclass  # noqa: E402

import numpy as np  # noqa: E402

from odohil.errors import MeasurementError  # noqa: E402
from odohil.science.estimators import Observation, estimate  # noqa: E402
from odohil.science.fisher import default_description  # noqa: E402
from odohil.science.floor_marks import MarkDistances, marks_from_pose, solve_marks  # noqa: E402
from odohil.science.moments import pose_moments  # noqa: E402
from odohil.science.parameters import NOMAD150, PARAMETER_NAMES  # noqa: E402
from odohil.science.paths import Design  # noqa: E402
from odohil.science.simulator import simulate  # noqa: E402

DESIGNS = (Design(1, 6.0), Design(20, 0.5))
CHUNK = 10


@dataclass(frozen=True)
class Replication:
    """One experiment: estimates, interval hits, verdict (or the failure)."""

    values: np.ndarray | None
    covered: np.ndarray | None
    verdict: str
    failure: str = ""
    outside_4sigma: np.ndarray | None = None


def tape_noise(rng: np.random.Generator, law: str, sigma: float, size: int) -> np.ndarray:
    """Tape errors with SD ``sigma`` (m): ``gauss`` or ``t3``."""
    if law == "gauss":
        return rng.normal(0.0, sigma, size)
    if law == "t3":
        return sigma / math.sqrt(3.0) * rng.standard_t(3, size)
    raise ValueError(f"unknown noise law {law!r}")


def run_chunk(args: tuple[int, str, str, int, int]) -> list[Replication]:
    """``count`` replications at ``n`` trials per design."""
    n, law, method, count, seed = args
    rng = np.random.default_rng(seed)
    description = default_description(0.001)
    truth = np.array(NOMAD150.as_tuple())
    priors = {d: pose_moments(d.path(), NOMAD150) for d in DESIGNS}
    out = []
    for _ in range(count):
        observations = []
        for design in DESIGNS:
            odometry = design.path().encoder_end_pose()
            poses = simulate(design.path(), NOMAD150, n, seed=rng).pose_change
            for pose in poses:
                exact = marks_from_pose(description, pose).as_array()
                noisy = np.abs(exact + tape_noise(rng, law, description.sigma_m, exact.size))
                marks = MarkDistances.of(description, noisy)
                try:
                    solution = solve_marks(description, marks, odometry, prior=priors[design])
                except MeasurementError:
                    continue  # the session would ask for the marks again
                observations.append(Observation(design, solution.pose_change, solution.cov))
        try:
            result = estimate(observations, method=method)  # type: ignore[arg-type]
        except Exception as exc:  # a failed fit is a result of the benchmark
            out.append(Replication(None, None, "error", f"{type(exc).__name__}: {exc}"))
            continue
        values = np.array([p.value for p in result.parameters])
        low = np.array([p.ci95[0] for p in result.parameters])
        high = np.array([p.ci95[1] for p in result.parameters])
        outside = np.array(
            [not p.contains(t) for p, t in zip(result.parameters, truth, strict=True)]
        )
        out.append(
            Replication(
                values, (low <= truth) & (truth <= high), result.verdict.status, "", outside
            )
        )
    return out


def summary(reps: list[Replication]) -> str:
    """One Markdown row block per parameter."""
    truth = np.array(NOMAD150.as_tuple())
    ok = [r for r in reps if r.values is not None and r.covered is not None]
    lines = []
    if ok:
        covered = np.array([r.covered for r in ok], dtype=float)
        values = np.array([r.values for r in ok])
        cover = covered.mean(axis=0)
        cover_se = np.sqrt(cover * (1 - cover) / len(ok))
        bias = (values.mean(axis=0) / truth - 1) * 100
        bias_se = values.std(axis=0, ddof=1) / math.sqrt(len(ok)) / np.abs(truth) * 100
        outside = np.array([r.outside_4sigma for r in ok], dtype=float).sum(axis=0)
        for i, name in enumerate(PARAMETER_NAMES):
            lines.append(
                f"{name}: coverage {cover[i]:.3f} +- {cover_se[i]:.3f}, "
                f"bias {bias[i]:+.2f} +- {bias_se[i]:.2f} %, "
                f"outside the 4-sigma interval {int(outside[i])}"
            )
    verdicts = {v: sum(r.verdict == v for r in reps) for v in ("trusted", "doubtful", "failed")}
    errors = [r.failure for r in reps if r.failure]
    first = f" ({errors[0]})" if errors else ""
    lines.append(f"verdicts {verdicts}, errors {len(errors)}{first}")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--replications", type=int, default=1000)
    parser.add_argument("--n", default="5,10,20,30", help="trials per design, comma-separated")
    parser.add_argument("--noise", default="gauss,t3", help="tape-noise laws: gauss, t3")
    parser.add_argument("--method", default="robust")
    parser.add_argument("--workers", type=int, default=1)
    parser.add_argument("--seed", type=int, default=20261123)
    parser.add_argument(
        "--max-seconds",
        type=float,
        default=None,
        help="stop after this wall time and report what is done (jobs run in shuffled order)",
    )
    args = parser.parse_args()
    print(f"command: python bench/coverage.py {' '.join(sys.argv[1:])}")
    print(f"load average before: {os.getloadavg()[0]:.2f}; {args.workers} workers", flush=True)
    seeds = iter(np.random.SeedSequence(args.seed).generate_state(100_000))
    start = time.perf_counter()
    cells = [(law, int(n)) for law in args.noise.split(",") for n in args.n.split(",")]
    jobs = []
    for law, n in cells:
        left = args.replications
        while left > 0:
            jobs.append((n, law, args.method, min(CHUNK, left), int(next(seeds))))
            left -= CHUNK
    order = np.random.default_rng(args.seed).permutation(len(jobs))
    jobs = [jobs[i] for i in order]
    results: dict[tuple[str, int], list[Replication]] = {cell: [] for cell in cells}
    with multiprocessing.Pool(args.workers) as pool:
        for job, chunk in zip(jobs, pool.imap(run_chunk, jobs), strict=False):
            results[(job[1], job[0])].extend(chunk)
            if args.max_seconds is not None and time.perf_counter() - start > args.max_seconds:
                print(f"stopped at --max-seconds {args.max_seconds:g}", flush=True)
                pool.terminate()
                break
    for law, n in cells:
        reps = results[(law, n)]
        print(f"\n## {law} tape noise, n = {n} per design ({len(reps)} replications)")
        print(summary(reps), flush=True)
    elapsed = time.perf_counter() - start
    print(f"\nwall clock {elapsed:.0f} s, load average after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
