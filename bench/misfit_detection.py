"""Benchmark: does the four-parameter fit see a turn-scale error it cannot model?

Usage: ``python bench/misfit_detection.py [--sets 1000] [--workers 2]
[--n-per-group 8] [--seed S] [--forth-back 0]``

Simulated general-path data sets of a differential drive whose turns are not
exact: per set, ``--n-per-group`` trials each of one-way straight runs of
1.5 m, UMBmark squares of 0.75 m (spins of 90 degrees) clockwise and
counter-clockwise, and circles of two laps at a radius of 0.3 m (cut into
16 legs and arc turns a lap) clockwise and counter-clockwise; the robot's
straight legs follow the paper's discrete model at the optiodom robot's
straight-run values (issue 20: E_R -0.63 deg/m, E_T -0.25 %, K_theta
0.24 deg^2/m, K_rho 3.6e-7 m) and each turn of encoder angle a turns the robot
by a (1 + e_turn) (the true path's turns scaled, simulated with
odohil/science/simulator.py); motion-capture noise 0.5 mm and 1 mrad.

Each set is fitted with the four-parameter model (turns declared exact) by
the general-path estimator, and its verdict read. The **bias** of a set is
|e_turn| times the circles' net turn (4 pi) in units of the circles' per-trial
heading standard deviation (sqrt(K_theta x 3.77 m + 1 mrad^2); the squares'
bias is 1/2 of the circles' in radians against a smaller SD). Reported per
bias size: the detection rate (verdict not trusted) with its binomial Monte
Carlo SE, and which checks fired; at bias 0 the false-alarm rate.

``--forth-back N``: also N clean data sets of forth-and-back designs
(k=1 l=3 m and k=10 l=0.5 m turn, 12 trials each, forwards and backwards) by
the forth-and-back estimator: the false-alarm rate the misfit checks add
there.
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

from collections.abc import Callable, Sequence  # noqa: E402
from dataclasses import dataclass  # noqa: E402

import numpy as np  # noqa: E402

from odohil.science.parameters import ErrorParameters  # noqa: E402
from odohil.science.path_trials import Direction, PathTrial  # noqa: E402
from odohil.science.paths import EncoderPath, Leg, Step, Turn  # noqa: E402
from odohil.science.simulator import simulate  # noqa: E402

TRUTH = ErrorParameters.from_paper_units(-0.63, -0.0025, 0.24, 3.6e-7)
"""The optiodom robot's straight-run values (issue 20)."""
MEASUREMENT_COV = np.diag([0.5e-3**2, 0.5e-3**2, 1e-3**2])
CIRCLE_RADIUS_M = 0.3
CIRCLE_LEGS_PER_LAP = 16
SQUARE_SIDE_M = 0.75
STRAIGHT_M = 1.5
BIAS_SIZES = (0.0, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 4.0)
"""Biases in per-trial SDs; 0 gets 3/10 of the sets, the others share the rest."""


def circle(ccw: bool, scale: float = 1.0) -> EncoderPath:
    """Two laps at CIRCLE_RADIUS_M, each lap CIRCLE_LEGS_PER_LAP legs and arc turns."""
    n = CIRCLE_LEGS_PER_LAP
    side = 2.0 * CIRCLE_RADIUS_M * math.sin(math.pi / n)
    turn = (2.0 * math.pi / n) * (1.0 if ccw else -1.0) * scale
    steps: list[Step] = []
    for _ in range(2 * n):
        steps += [Leg(side), Turn(turn, "arc")]
    return EncoderPath(tuple(steps), name=f"circle {'ccw' if ccw else 'cw'}")


def square(ccw: bool, scale: float = 1.0) -> EncoderPath:
    """UMBmark square: 4 legs of SQUARE_SIDE_M, a 90 degree spin after each."""
    turn = (math.pi / 2.0) * (1.0 if ccw else -1.0) * scale
    steps: list[Step] = []
    for _ in range(4):
        steps += [Leg(SQUARE_SIDE_M), Turn(turn, "spin")]
    return EncoderPath(tuple(steps), name=f"square {'ccw' if ccw else 'cw'}")


def straight() -> EncoderPath:
    return EncoderPath((Leg(STRAIGHT_M),), name="straight")


GROUPS: tuple[tuple[str, Direction, Callable[[float], EncoderPath]], ...] = (
    ("straight", "forward", lambda s: straight()),
    ("square", "cw", lambda s: square(False, s)),
    ("square", "ccw", lambda s: square(True, s)),
    ("arc", "cw", lambda s: circle(False, s)),
    ("arc", "ccw", lambda s: circle(True, s)),
)


def heading_sd() -> float:
    """The circles' per-trial heading SD, rad (the bias's unit)."""
    distance = circle(True).distance_m
    return math.sqrt(TRUTH.k_theta * distance + MEASUREMENT_COV[2, 2])


def e_turn_for(bias_sd: float, sign: float) -> float:
    """The turn-scale error whose heading bias on a circle is ``bias_sd`` SDs."""
    return sign * bias_sd * heading_sd() / (4.0 * math.pi)


def data_set(e_turn: float, n: int, rng: np.random.Generator) -> list[PathTrial]:
    """One simulated data set (module docstring), in driving order per group."""
    trials: list[PathTrial] = []
    for family, direction, make in GROUPS:
        nominal = make(1.0)
        true_path = make(1.0 + e_turn)
        poses = simulate(true_path, TRUTH, n, seed=rng).pose_change
        poses[:, 2] += true_path.winding_rad - nominal.winding_rad
        poses = poses + rng.multivariate_normal(np.zeros(3), MEASUREMENT_COV, size=n)
        for pose in poses:
            trials.append(
                PathTrial(
                    nominal,
                    pose,
                    MEASUREMENT_COV,
                    source=f"sim/{family}-{direction}",
                    trial=len(trials) + 1,
                    family=family,
                    direction=direction,
                )
            )
    return trials


@dataclass(frozen=True)
class Outcome:
    bias_sd: float
    e_turn: float
    status: str
    misfit_failed: bool
    global_failed: bool
    kinds: tuple[str, ...]
    seconds: float
    error: str = ""


def fit_four(trials: Sequence[PathTrial]) -> tuple[str, bool, bool, tuple[str, ...]]:
    """The four-parameter fit's verdict: (status, misfit failed, global
    check failed, kinds of misfit tests that fired)."""
    from odohil.science.estimators.paths import estimate_paths

    result = estimate_paths(list(trials), turns_exact=True)
    misfit = result.misfit
    kinds = tuple(sorted({t.kind for t in misfit.failed()})) if misfit is not None else ()
    return (
        result.verdict.status,
        misfit is not None and not misfit.passed,
        not result.model_check.fits,
        kinds,
    )


def _one(job: tuple[int, float, int, int]) -> Outcome:
    index, bias_sd, n, seed = job
    rng = np.random.default_rng([seed, index])
    sign = 1.0 if index % 2 == 0 else -1.0
    e = e_turn_for(bias_sd, sign)
    trials = data_set(e, n, rng)
    start = time.process_time()
    try:
        status, misfit_failed, global_failed, kinds = fit_four(trials)
    except Exception as exc:  # a benchmark counts what fails
        return Outcome(bias_sd, e, "error", False, False, (), 0.0, f"{type(exc).__name__}: {exc}")
    return Outcome(
        bias_sd, e, status, misfit_failed, global_failed, kinds, time.process_time() - start
    )


def _forth_back_one(job: tuple[int, int]) -> tuple[str, bool]:
    from odohil.science.estimators import Observation, estimate
    from odohil.science.paths import Design

    index, seed = job
    rng = np.random.default_rng([seed, 7, index])
    obs = []
    meas = np.diag([1e-6, 1e-6, 4e-6])
    params = ErrorParameters.from_paper_units(-0.5, -0.02, 0.1, 1e-4)
    for design in (
        Design(1, 3.0),
        Design(1, 3.0, backward=True),
        Design(10, 0.5),
        Design(10, 0.5, backward=True),
    ):
        poses = simulate(design.path(), params, 12, seed=rng).pose_change
        poses = poses + rng.multivariate_normal(np.zeros(3), meas, size=12)
        obs += [Observation(design, p, meas) for p in poses]
    result = estimate(obs)
    return result.verdict.status, result.misfit is not None and not result.misfit.passed


def _rate(k: int, n: int) -> str:
    if n == 0:
        return "-"
    p = k / n
    return f"{p:.3f} +- {math.sqrt(max(p * (1 - p), 1.0 / n) / n):.3f}"


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--sets", type=int, default=1000)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--n-per-group", type=int, default=8)
    parser.add_argument("--seed", type=int, default=20)
    parser.add_argument("--forth-back", type=int, default=0)
    args = parser.parse_args()
    if args.workers > 2:
        sys.exit("--workers: at most 2 (the machine is shared)")
    clean = round(0.3 * args.sets)
    per_size = (args.sets - clean) // (len(BIAS_SIZES) - 1)
    jobs: list[tuple[int, float, int, int]] = []
    for size in BIAS_SIZES:
        count = clean if size == 0 else per_size
        jobs += [(len(jobs) + i, size, args.n_per_group, args.seed) for i in range(count)]
    print(
        f"{len(jobs)} sets x {len(GROUPS) * args.n_per_group} trials; load average before: "
        f"{os.getloadavg()[0]:.2f}; {args.workers} workers; circle heading SD "
        f"{math.degrees(heading_sd()):.3f} deg (1 SD of bias: e_turn "
        f"{100 * e_turn_for(1.0, 1.0):.4f} %)",
        flush=True,
    )
    wall = time.time()
    with multiprocessing.Pool(args.workers) as pool:
        outcomes = pool.map(_one, jobs, chunksize=4)
        fb = pool.map(_forth_back_one, [(i, args.seed) for i in range(args.forth_back)])
    print(f"wall {time.time() - wall:.0f} s; load average after: {os.getloadavg()[0]:.2f}")
    print(
        "| bias (SD) | e_turn | sets | not trusted | misfit failed | global failed | "
        "fired (spread/group/order) | errors | CPU s/fit |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    for size in BIAS_SIZES:
        mine = [o for o in outcomes if o.bias_sd == size]
        n = len(mine)
        bad = sum(o.status != "trusted" for o in mine)
        mis = sum(o.misfit_failed for o in mine)
        glob = sum(o.global_failed for o in mine)
        fired = "/".join(
            str(sum(kind in o.kinds for o in mine)) for kind in ("spread", "group", "order")
        )
        errors = sum(o.status == "error" for o in mine)
        cpu = np.mean([o.seconds for o in mine if o.status != "error"] or [math.nan])
        print(
            f"| {size:g} | {100 * e_turn_for(size, 1.0):.3f} % | {n} | {_rate(bad, n)} | "
            f"{_rate(mis, n)} | {_rate(glob, n)} | {fired} | {errors} | {cpu:.2f} |"
        )
    for o in outcomes:
        if o.error:
            print("error:", o.error)
            break
    if fb:
        n = len(fb)
        untrusted = sum(s != "trusted" for s, _ in fb)
        print(
            f"forth-and-back clean sets: {n}; not trusted {_rate(untrusted, n)}; "
            f"misfit failed {_rate(sum(m for _, m in fb), n)}"
        )


if __name__ == "__main__":
    main()
