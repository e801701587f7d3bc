"""Issue 31's diagnosis: the calibrated robot's false-rejection rate, per test,
conditional on each of 100 calibrations (bench/validation_power.py's, same
seeds), averaged over many validation sets of a fixed count drawn on the true
robot by the discrete model.

Per robot, seed and path: REPS sets of N trials tested by ``check_trials``;
prints the verdict's and each test's rejection rate (all sets of all seeds;
the Monte Carlo SE is dominated by the 100 calibrations).

Run: nice -n 10 python bench/validation_level.py [--seeds 100] [--reps 100] [--trials 15]
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))

from validation_power import _CALIBRATIONS, _measured, _paths, _robots  # noqa: E402

from odohil.science.estimators import Observation, estimate  # noqa: E402
from odohil.session.results.validation import ValidationTrials, check_trials  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=100)
    parser.add_argument("--reps", type=int, default=100)
    parser.add_argument("--trials", type=int, default=15)
    args = parser.parse_args()
    start, cpu = time.time(), time.process_time()
    n = args.trials
    for robot, (description, truth, turns_exact) in _robots().items():
        rejected: dict[str, list[np.ndarray]] = {}
        for seed in range(1, args.seeds + 1):
            rng = np.random.default_rng([31, seed, robot == "create2"])
            observations = []
            for design, count in _CALIBRATIONS[robot]:
                poses, covs = _measured(design.path(), truth, count, description, rng)
                observations += [
                    Observation(design, p, c) for p, c in zip(poses, covs, strict=True)
                ]
            result = estimate(observations, turns_exact=turns_exact)
            for direction, vpath in _paths(robot):
                assert vpath.path is not None
                for _ in range(args.reps):
                    poses, covs = _measured(vpath.path, truth, n, description, rng)
                    trials = ValidationTrials(
                        poses, covs, (vpath.path,) * n, (vpath.text,) * n,
                        tuple(range(1, n + 1)), (False,) * n,
                    )  # fmt: skip
                    tested = check_trials(trials, result, 0.01)
                    row = np.array([not tested.passed] + [not t.passed for t in tested.tests])
                    rejected.setdefault(direction, []).append(row)
        names = ["verdict", "overall", "x", "y", "theta", "bias", "bias x", "bias y", "bias theta"]
        for direction, rows in rejected.items():
            rates = np.mean(rows, axis=0)
            print(f"{robot} {direction}: " + ", ".join(
                f"{name} {rate:.4f}" for name, rate in zip(names, rates, strict=True)))  # fmt: skip
    print(f"load {os.getloadavg()[0]:.2f}; {time.time() - start:.0f} s wall, "
          f"{time.process_time() - cpu:.0f} s CPU")  # fmt: skip


if __name__ == "__main__":
    main()
