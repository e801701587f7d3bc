"""How long a general-path fit takes: 100 trials of 40 legs each (issue 20:
under 5 s on one core).

Each trial is a random path of 40 legs (0.1 to 0.4 m, some driven backwards)
joined by turns: spins of up to 90 degrees and arc turns of up to 20 degrees,
either direction, simulated with a turn-scale error
(odohil/science/diff_drive.py simulate_turn_errors) and fitted by
odohil/science/estimators/paths.py estimate_paths with turns_exact=False.
Reported: CPU time (time.process_time: the machine is shared, wall time
would count the others) of the Gaussian maximum-likelihood fit alone (point
estimate and standard errors) and of the whole estimate (the split-by-direction
test, robust fit, intervals, checks); with ``--breakdown``, where one more
whole estimate spends its time (cProfile, cumulative CPU per stage; the
profiler adds its own overhead).

    taskset -c 0 python bench/path_fit_speed.py [--repeat 3] [--breakdown]
"""

from __future__ import annotations

import argparse
import cProfile
import math
import pstats
import statistics
import time

import numpy as np

from odohil.science.diff_drive import simulate_turn_errors
from odohil.science.estimators.paths import estimate_paths, fit_paths
from odohil.science.moments import TurnErrors
from odohil.science.parameters import ErrorParameters
from odohil.science.path_trials import PathTrial
from odohil.science.paths import EncoderPath, Leg, Step, Turn

TRUTH = ErrorParameters.from_paper_units(-0.5, -0.003, 0.2, 4e-7)
TURNS = TurnErrors(-0.007, -0.007, -0.012, -0.012, k_spin=1e-4)
MEASUREMENT = np.diag([1e-8, 1e-8, 1e-6])


def random_path(rng: np.random.Generator, n_legs: int = 40) -> EncoderPath:
    """A path of ``n_legs`` legs with spins and arc turns between them."""
    steps: list[Step] = []
    for i in range(n_legs):
        length = float(rng.uniform(0.1, 0.4)) * (1.0 if rng.random() < 0.85 else -1.0)
        steps.append(Leg(length))
        if i < n_legs - 1:
            if rng.random() < 0.3:
                steps.append(Turn(float(rng.uniform(-math.pi / 2, math.pi / 2)), "spin"))
            else:
                steps.append(Turn(float(rng.uniform(-0.35, 0.35)), "arc"))
    return EncoderPath(tuple(steps), name="random 40 legs")


def trials(n: int, seed: int) -> list[PathTrial]:
    """``n`` simulated trials, each on its own random path."""
    rng = np.random.default_rng(seed)
    out = []
    for i in range(n):
        path = random_path(rng)
        pose = simulate_turn_errors(path, TRUTH, TURNS, 1, seed=rng, segment_m=0.01).pose_change[0]
        pose = pose + rng.multivariate_normal(np.zeros(3), MEASUREMENT)
        out.append(PathTrial(path, pose, MEASUREMENT, trial=i + 1, family="random"))
    return out


STAGES = (
    ("maximum-likelihood fits (one e_turn, and split by direction)", "paths.py", "_fit"),
    ("robust EM", "robust.py", "robust_em"),
    ("profile intervals (K_theta, K_rho, K_spin)", "intervals.py", "profile_interval"),
    ("Satterthwaite degrees of freedom", "intervals.py", "satterthwaite_dofs"),
    ("misfit checks", "paths.py", "_misfit"),
)


def breakdown(data: list[PathTrial]) -> None:
    """Print the cumulative CPU time of each stage of one whole estimate."""
    profiler = cProfile.Profile(time.process_time)
    profiler.enable()
    estimate_paths(data, turns_exact=False)
    profiler.disable()
    stats = pstats.Stats(profiler)
    table = stats.stats  # type: ignore[attr-defined]
    total = max(entry[3] for entry in table.values())
    print(f"where one estimate spends its time (cProfile, {total:.2f} s CPU):")
    for label, module, name in STAGES:
        spent = sum(
            entry[3]
            for (path, _, function), entry in table.items()
            if function == name and path.endswith(module)
        )
        print(f"  {label}: {spent:.2f} s")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=100)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--breakdown", action="store_true", help="profile one more estimate")
    args = parser.parse_args()
    data = trials(args.trials, args.seed)
    fit_times, full_times = [], []
    for _ in range(args.repeat):
        start = time.process_time()
        fit_paths(data, turns_exact=False, split_directions=False)
        fit_times.append(time.process_time() - start)
        start = time.process_time()
        result = estimate_paths(data, turns_exact=False)
        full_times.append(time.process_time() - start)
    print(f"{args.trials} trials x 40 legs, {result.verdict.status}")
    for p in result.parameters:
        print(f"  {p.name}: {p.value:.4g} [{p.ci95[0]:.4g}, {p.ci95[1]:.4g}]")
    print(f"  notes: {'; '.join(result.notes)}")
    print(
        f"maximum-likelihood fit: median {statistics.median(fit_times):.2f} s "
        f"(runs {', '.join(f'{t:.2f}' for t in fit_times)})"
    )
    print(
        f"whole estimate (robust fit, intervals, checks): median "
        f"{statistics.median(full_times):.2f} s (runs {', '.join(f'{t:.2f}' for t in full_times)})"
    )
    if args.breakdown:
        breakdown(data)


if __name__ == "__main__":
    main()
