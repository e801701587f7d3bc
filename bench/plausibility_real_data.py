"""The per-trial check (odohil/session/measure/plausibility.py) on real straight runs.

The optiodom data set's straight runs (``ivanjko`` sessions: a real
differential-drive robot, OptiTrack ground truth at the robot's centre, see
the data set's README) are judged as a motion-capture session would judge
them at the robot description's default ``[priors]`` (the Nomad 150's, not
this robot's): each run's encoder path from the wheel counts with the nominal
geometry, its measured pose change the ground truth at rest (pose_sigma 0.5
mm, 0.5 mm, 1 mrad) and its path's farthest point. Then the same runs as a
frozen stream would report them (the robot never moved) and as a stream in
millimetres. Prints one line per case: runs, refused, flagged, the largest
and median T.

Run: python bench/plausibility_real_data.py DATA/ivanjko
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

from odohil.science.paths import Design
from odohil.science.pose_selection import ParameterBelief, predictive_pose
from odohil.science.robot_description import ParameterPriors
from odohil.session.measure.plausibility import judge
from odohil.session.measure.protocol import MeasuredPose, Pose
from odohil.units import wrap_angle

WHEEL_D_M, WHEEL_BASE_M, COUNTS_PER_TURN = 0.084, 0.20, 2796.8
POSE_SIGMA = np.array([0.0005, 0.0005, 0.001])


def runs(folder: Path) -> list[tuple[Pose, Pose, list[tuple[float, ...]], float]]:
    """(encoder end pose, true pose change, encoder path, true farthest point)
    of each straight run (in-place turns are left out)."""
    metres = math.pi * WHEEL_D_M / COUNTS_PER_TURN
    found = []
    for file in sorted(folder.glob("*/*_run-*.csv")):
        rows = np.loadtxt(file, delimiter=",")
        x = y = theta = 0.0
        path = []
        for row in rows:
            right, left = row[4] * metres, row[5] * metres
            ds, dtheta = (right + left) / 2, (right - left) / WHEEL_BASE_M
            x += ds * math.cos(theta + dtheta / 2)
            y += ds * math.sin(theta + dtheta / 2)
            theta += dtheta
            path.append((float(row[0]), x, y, theta))
        if math.hypot(x, y) < 1.0:
            continue  # an in-place turn
        encoders = (x, y, wrap_angle(theta))
        true = (float(rows[-1, 1]), float(rows[-1, 2]), wrap_angle(float(rows[-1, 3])))
        farthest = float(np.hypot(rows[:, 1], rows[:, 2]).max())
        found.append((encoders, true, path, farthest))
    return found


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder", type=Path, help="the data set's ivanjko folder")
    folder = parser.parse_args().folder
    belief = ParameterBelief.from_priors(ParameterPriors())
    c = 2.0 * POSE_SIGMA**2
    cov = ((c[0], 0.0, 0.0), (0.0, c[1], 0.0), (0.0, 0.0, c[2]))
    cases = {
        "as measured": lambda p, e: (p, e),
        "frozen stream": lambda p, e: ((0.0002, -0.0001, 0.0004), 0.003),
        "millimetres": lambda p, e: ((p[0] * 1e3, p[1] * 1e3, p[2]), e * 1e3),
    }
    found = runs(folder)
    for name, make in cases.items():
        refused = flagged = 0
        stats = []
        causes: set[str] = set()
        for encoders, true, path, farthest in found:
            pose, excursion = make(true, farthest)
            design = Design(0.5, round(math.hypot(*encoders[:2]), 1))
            predicted = predictive_pose(design, belief, encoders)
            measured = MeasuredPose(pose=pose, covariance=cov, excursion_m=excursion)
            judged = judge(1, measured, predicted, encoders, path)
            stats.append(judged.measured.details["check"]["T"])
            refused += bool(judged.refusal)
            flagged += judged.measured.flagged
            if judged.refusal:
                causes.add(judged.refusal.split(": ")[3].split("?")[0] + "?")
        print(
            f"{name}: {len(found)} runs, {refused} refused ({', '.join(sorted(causes))}), "
            f"{flagged} flagged; T max {max(stats):.3g}, median {np.median(stats):.3g}"
        )


if __name__ == "__main__":
    main()
