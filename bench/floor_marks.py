"""Benchmark: solving floor marks for simulated design A and B trials.

Reports the time per trial and how often a trial is clear-cut, with one or two
cross distances, without and with the model's prior (pose moments at the true
parameters). Run: python bench/floor_marks.py
"""

from __future__ import annotations

import time

import numpy as np

from odohil.science.floor_marks import MarkDistances, marks_from_pose, solve_marks
from odohil.science.moments import pose_moments
from odohil.science.parameters import NOMAD150
from odohil.science.paths import Design
from odohil.science.robot_description import RobotDescription, Screw
from odohil.science.simulator import simulate

SCREWS = (Screw("A", 0.2, 0.0), Screw("B", -0.1, 0.1732), Screw("C", -0.1, -0.1732))
N_TRIALS = 100


def main() -> None:
    rng = np.random.default_rng(1)
    for design in (Design(1, 6.0), Design(20, 0.5)):
        path = design.path()
        poses = simulate(path, NOMAD150, N_TRIALS, seed=7).pose_change
        prior = pose_moments(path, NOMAD150)
        odometry = path.encoder_end_pose()
        for cross in ((("A", "B"),), (("A", "B"), ("B", "C"))):
            description = RobotDescription(SCREWS, sigma_m=0.001, cross_pairs=cross)
            for use_prior in (False, True):
                clear = wrong = 0
                start = time.perf_counter()
                for pose in poses:
                    exact = marks_from_pose(description, pose).as_array()
                    noisy = np.abs(exact + rng.normal(0.0, 0.001, exact.size))
                    marks = MarkDistances.of(description, noisy)
                    solution = solve_marks(
                        description, marks, odometry, prior=prior if use_prior else None
                    )
                    error = np.abs(solution.pose_change - pose) / np.sqrt(np.diag(solution.cov))
                    clear += solution.clear_cut
                    wrong += bool(solution.clear_cut and error.max() > 5)
                elapsed = (time.perf_counter() - start) / len(poses) * 1000
                print(
                    f"{design.label():>18}  cross={len(cross)}  prior={use_prior!s:5}  "
                    f"clear-cut {clear}/{len(poses)}  wrong-and-clear {wrong}  "
                    f"{elapsed:.1f} ms/trial"
                )


if __name__ == "__main__":
    main()
