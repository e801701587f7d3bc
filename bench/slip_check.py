"""Benchmark: the slip check on clean tape and on a 5 mm slip, over robots far
from the paper's Nomad (issue 31).

Usage: ``nice -n 10 python bench/slip_check.py [--sessions 8] [--seed 31]``

Each session is the issue's plan (k=1 l=3 n=15; k=5 l=1 n=15; k=0.5 l=3
n=10, one-way trials alternating direction as a session drives them) on a
robot of the grid, with the paper's motion (``turn``, the Nomad) or the
Create 2's turn-free one (``reverse``), with and without ``[priors]`` (given:
the robot's own values with the default deviations). Each trial: the true
pose change from the discrete model (odohil/science/simulator.py), five
distances read with 1 mm Gaussian noise, predicted as the engine predicts it
(odohil/session/run/engine.py: the running incremental estimate as a belief,
the priors before there is one), solved and checked by
odohil/science/pose_selection.py. Counted per cell: the **false-alarm rate**
(clean trials that trip the check, i.e. would be re-measured) and the
**catch rate** of a 5 mm slip (the same readings with one distance, chosen at
random, off by +-5 mm), each with its binomial Monte Carlo SE. The estimate
is fed the clean trial. Forth-and-back paths only (the general paths'
belief is the recipe's fit of every trial, too slow for this budget).
"""

from __future__ import annotations

import argparse
import contextlib
import math
import os
import time

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402

from odohil.errors import OdohilError  # noqa: E402
from odohil.science.estimators import IncrementalEstimator, Observation  # noqa: E402
from odohil.science.floor_marks import MarkDistances, marks_from_pose  # noqa: E402
from odohil.science.parameters import ErrorParameters  # noqa: E402
from odohil.science.paths import Design, floor_choreography  # noqa: E402
from odohil.science.pose_selection import (  # noqa: E402
    ParameterBelief,
    predictive_pose,
    select_pose,
)
from odohil.science.robot_description import (  # noqa: E402
    ParameterPriors,
    RobotDescription,
    Screw,
)
from odohil.science.simulator import simulate  # noqa: E402

SCREWS = (Screw("A", 0.2, 0.0), Screw("B", -0.1, 0.173), Screw("C", -0.1, -0.173))
SLIP_M = 0.005
ROBOTS = {  # paper units: E_R deg/m, E_T, K_theta deg^2/m, K_rho m
    "Nomad 150": (-0.202, -0.02, 0.012, 3.6e-5),
    "real robot": (-0.15, -0.02, 0.39, 3.6e-5),
    "E_R -1, K_th 0.5": (-1.0, -0.02, 0.5, 3.6e-5),
    "-2, +5 %, 1, 1e-6": (-2.0, 0.05, 1.0, 1e-6),
    "+2, -5 %, 1, 1e-3": (2.0, -0.05, 1.0, 1e-3),
    "+2, +5 %, 0.001, 1e-6": (2.0, 0.05, 0.001, 1e-6),
    "-2, -5 %, 0.001, 1e-3": (-2.0, -0.05, 0.001, 1e-3),
}
PLAN = ((1.0, 3.0, 15), (5.0, 1.0, 15), (0.5, 3.0, 10))


def session(
    truth: ErrorParameters, variant: str, given: bool, rng: np.random.Generator
) -> tuple[int, int, int]:
    """(trials, clean trials tripped, slipped trials caught) of one session."""
    priors = ParameterPriors(mean=truth, given=True) if given else ParameterPriors()
    description = RobotDescription(SCREWS, 0.001, (("A", "B"), ("B", "C")), priors=priors)
    choreography = floor_choreography([(Design(k, length, variant), n) for k, length, n in PLAN])  # type: ignore[arg-type]
    estimator = IncrementalEstimator()
    n = tripped = caught = 0
    for trial in range(1, choreography.n_trials + 1):
        design = choreography.trial(trial)[0]
        pose = simulate(design.path(), truth, 1, seed=rng).pose_change[0]
        exact = marks_from_pose(description, pose).as_array()
        readings = exact + rng.normal(0.0, description.sigma_m, exact.size)
        belief = ParameterBelief.from_priors(priors)
        if estimator.fit is not None:
            with contextlib.suppress(OdohilError):
                belief = ParameterBelief.from_result(estimator.result(), priors)
        odometry = design.path().encoder_end_pose()
        predicted = predictive_pose(design, belief, odometry)
        try:
            clean = select_pose(
                description, MarkDistances.of(description, readings), odometry, predicted
            )
        except OdohilError:
            continue  # no rigid motion explains clean readings: the tape's own test
        n += 1
        tripped += clean.slip.tripped
        slipped = readings.copy()
        slipped[int(rng.integers(slipped.size))] += SLIP_M * float(rng.choice((-1.0, 1.0)))
        try:
            caught += select_pose(
                description, MarkDistances.of(description, slipped), odometry, predicted
            ).slip.tripped
        except OdohilError:
            caught += 1  # refused as no rigid motion: caught too
        if not clean.ambiguous:
            observation = Observation(
                design, clean.solution.pose_change, clean.solution.cov, trial=trial
            )
            with contextlib.suppress(OdohilError):
                estimator.add(observation)
    return n, tripped, caught


def rate(hits: int, total: int) -> str:
    """``p +- SE`` in percent."""
    p = hits / total
    return f"{100 * p:.2f} +- {100 * math.sqrt(max(p * (1 - p), 1.0 / total) / total):.2f}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sessions", type=int, default=8)
    parser.add_argument("--seed", type=int, default=31)
    args = parser.parse_args()
    rng = np.random.default_rng(args.seed)
    start = time.process_time()
    total = [0, 0, 0]
    columns = ("robot (E_R, E_T, K_theta, K_rho)", "motion", "[priors]", "trials")
    print("| " + " | ".join((*columns, "false alarms %", "5 mm caught %")) + " |")
    print("|---|---|---|---|---|---|")
    for name, paper in ROBOTS.items():
        truth = ErrorParameters.from_paper_units(*paper)
        for variant in ("turn", "reverse"):
            for given in (False, True):
                cell = [0, 0, 0]
                for _ in range(args.sessions):
                    for i, v in enumerate(session(truth, variant, given, rng)):
                        cell[i] += v
                total = [a + b for a, b in zip(total, cell, strict=True)]
                print(
                    f"| {name} | {variant} | {'yes' if given else 'no'} | {cell[0]} | "
                    f"{rate(cell[1], cell[0])} | {rate(cell[2], cell[0])} |",
                    flush=True,
                )
    print(f"| all | | | {total[0]} | {rate(total[1], total[0])} | {rate(total[2], total[0])} |")
    print(f"CPU {time.process_time() - start:.0f} s")


if __name__ == "__main__":
    main()
