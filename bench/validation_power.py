"""Issue 31, "validation sized by power": with the trial count ``validate
--detect`` plans, is the wrong robot (E_R x3, K_theta x9) rejected in >= 95 %
of validations and the calibrated one passed in >= 95 %?

Per robot and seed: a calibration (the Nomad: tests/cli/test_validate.py's
plan ``k=1,l=3,n=12;k=10,l=0.5,n=12``, README robot; the Create 2: the
built-in description, turn-free ``reverse`` designs ``k=0.5,l=3,n=12;
k=1.5,l=1,n=12``), estimated by the recipe's estimator (robust maximum
likelihood, odohil/science/estimators); then, per direction, the count
``size_validation`` plans for ``--detect E_R=2|E_R|,K_theta=8 K_theta`` (the
wrong robot's errors, each alone; the session API of ``validate --detect``,
odohil/session/commands/validate_power.py) is drawn on the calibrated robot
and on the wrong one and tested by ``check_trials`` (the session API of
``validate``). Paths: the Nomad a 1 m square, cw and ccw; the Create 2 (turn
free) the one-way ``forth-back:0.5,4,reverse``, driven forwards and backwards.

Truth: the science simulator (odohil/science/simulator.py, the discrete model
the fakes drive with), not the fakes over their URL handlers: the fakes'
Create 2 costs minutes a calibration (bench/validate_paths.py), and what is
measured here is the planned count's power, which the driver and the tape do
not change. Each trial's pose is measured with Gaussian noise of the tape's
covariance at that pose (odohil/science/floor_marks.py ``pose_covariance``,
the robot's description), given to the estimator and the test as the tape
gives it.

Run: nice -n 10 python bench/validation_power.py [--seeds 20]
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from fakes.create2.config import CREATE2_TRUTH  # noqa: E402
from odohil.science.estimators import Observation, estimate  # noqa: E402
from odohil.science.floor_marks import pose_covariance  # noqa: E402
from odohil.science.parameters import NOMAD150, ErrorParameters  # noqa: E402
from odohil.science.paths import Design, EncoderPath, square  # noqa: E402
from odohil.science.robot_description import RobotDescription  # noqa: E402
from odohil.science.simulator import simulate  # noqa: E402
from odohil.session.commands.validate_power import size_validation  # noqa: E402
from odohil.session.results.validation import (  # noqa: E402
    ValidationPath,
    ValidationTrials,
    check_trials,
)
from odohil.session.robots.description import builtin_path, load_robot_description  # noqa: E402
from odohil.session.robots.registry import parse_description  # noqa: E402
from odohil.units import rad2_per_m_to_deg2_per_m, rad_per_m_to_deg_per_m  # noqa: E402
from tests.session.test_trust_runs import readme_robot  # noqa: E402

ALPHA = 0.01
SEGMENT_M = 0.01


def _robots() -> dict[str, tuple[RobotDescription, ErrorParameters, bool]]:
    """name -> (description, truth, turns exact)."""
    return {
        "nomad150": (parse_description(readme_robot(), "robot.toml"), NOMAD150, True),
        "create2": (load_robot_description(builtin_path("create2")), CREATE2_TRUTH, False),
    }


_CALIBRATIONS = {
    "nomad150": ((Design(1, 3.0, "turn"), 12), (Design(10, 0.5, "turn"), 12)),
    "create2": ((Design(0.5, 3.0, "reverse"), 12), (Design(1.5, 1.0, "reverse"), 12)),
}
"""The calibration plans: the Nomad's of tests/cli/test_validate.py; the
Create 2's turn free with an odd number of legs (a closed reverse design's
signed distance is 0: it says nothing of E_R)."""


def _paths(robot: str) -> list[tuple[str, ValidationPath]]:
    if robot == "nomad150":
        out = []
        for direction in ("cw", "ccw"):
            text = f"square:1.0,{direction}"
            path = square(1.0, counter_clockwise=direction == "ccw")
            out.append((direction, _vpath(text, path, None)))
        return out
    forward = Design(0.5, 4.0, "reverse")
    backward = replace(forward, backward=True)
    return [
        ("forward", _vpath("forth-back:0.5,4,reverse", forward.path(), forward)),
        ("backward", _vpath("forth-back:0.5,4,reverse (backward)", backward.path(), backward)),
    ]


def _vpath(text: str, path: EncoderPath, design: Design | None) -> ValidationPath:
    if design is not None:
        return ValidationPath("forth-back", text, design=design, path=path)
    from odohil.science.path_designs import parse_path_design

    shape = parse_path_design(text)
    return ValidationPath("path", text, path=shape.path(), shape=shape)


def _measured(
    path: EncoderPath, truth: ErrorParameters, n: int, description: RobotDescription,
    rng: np.random.Generator,
) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """n trials' measured poses and their tape covariances."""
    poses = simulate(path, truth, n, seed=rng, segment_m=SEGMENT_M).pose_change
    covs = np.array([pose_covariance(description, p) for p in poses])
    noisy = np.array([rng.multivariate_normal(p, c) for p, c in zip(poses, covs, strict=True)])
    return noisy, covs


def _cell(robot: str, seed: int) -> list[dict[str, object]]:
    description, truth, turns_exact = _robots()[robot]
    rng = np.random.default_rng([31, seed, robot == "create2"])
    observations = []
    plan = _CALIBRATIONS[robot]
    for design, n in plan:
        poses, covs = _measured(design.path(), truth, n, description, rng)
        observations += [Observation(design, p, c) for p, c in zip(poses, covs, strict=True)]
    result = estimate(observations, turns_exact=turns_exact)
    wrong = replace(truth, e_r=3 * truth.e_r, k_theta=9 * truth.k_theta)
    detect = (
        f"E_R={rad_per_m_to_deg_per_m(wrong.e_r - truth.e_r):.6g},"
        f"K_theta={rad2_per_m_to_deg2_per_m(wrong.k_theta - truth.k_theta):.6g}"
    )
    rows = []
    for direction, vpath in _paths(robot):
        assert vpath.path is not None
        sizing = size_validation(
            detect, vpath, result, description, measure="fake", trials=None, alpha=ALPHA
        )
        outcome = {}
        for name, params in (("calibrated", truth), ("wrong", wrong)):
            poses, covs = _measured(vpath.path, params, sizing.trials, description, rng)
            trials = ValidationTrials(
                poses, covs, (vpath.path,) * sizing.trials, (vpath.text,) * sizing.trials,
                tuple(range(1, sizing.trials + 1)), (False,) * sizing.trials,
            )  # fmt: skip
            outcome[name] = check_trials(trials, result, ALPHA).passed
        rows.append(
            {
                "robot": robot, "direction": direction, "seed": seed,
                "trusted": result.verdict.trusted, "trials": sizing.trials,
                "power": min(c.power for c in sizing.caught),
                "calibrated_passed": outcome["calibrated"], "wrong_rejected": not outcome["wrong"],
            }
        )  # fmt: skip
    return rows


def _se(p: float, k: int) -> float:
    """The Monte Carlo SE of a rate p of k (at p = 0 or 1, that of 1 in k)."""
    return math.sqrt(max(p * (1 - p), 1 / k) / k)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=20)
    args = parser.parse_args()
    start, cpu = time.time(), time.process_time()
    rows = [row for robot in _robots() for seed in range(1, args.seeds + 1)
            for row in _cell(robot, seed)]  # fmt: skip
    print(f"load {os.getloadavg()[0]:.2f}; {len(rows)} validations x 2; "
          f"{time.time() - start:.0f} s wall, {time.process_time() - cpu:.0f} s CPU")  # fmt: skip
    print("| robot | path | seeds | planned trials (min-median-max) | planned power (min) "
          "| calibrated passes | wrong rejected |")  # fmt: skip
    print("|---|---|---|---|---|---|---|")
    for robot in _robots():
        for direction, vpath in _paths(robot):
            mine = [r for r in rows if r["robot"] == robot and r["direction"] == direction]
            k = len(mine)
            counts = [int(str(r["trials"])) for r in mine]
            passed = sum(bool(r["calibrated_passed"]) for r in mine) / k
            rejected = sum(bool(r["wrong_rejected"]) for r in mine) / k
            untrusted = sum(not r["trusted"] for r in mine)

            print(
                f"| {robot} | {vpath.text} | {k}{f' ({untrusted} untrusted)' if untrusted else ''}"
                f" | {min(counts)}-{int(np.median(counts))}-{max(counts)}"
                f" | {min(float(str(r['power'])) for r in mine):.3f}"
                f" | {passed:.2f} (SE {_se(passed, k):.2f})"
                f" | {rejected:.2f} (SE {_se(rejected, k):.2f}) |"
            )


if __name__ == "__main__":
    main()
