"""Benchmark: the slip check on clean tape and on a 5 mm slip in sessions
with general paths, over the robots of issue 31's grid, on the Nomad 150 and
the Create 2.

Usage: ``nice -n 10 python bench/slip_check_paths.py [--sessions 4] [--seed 31] [--before]``

Per cell (a robot of the grid, the Nomad 150's or the Create 2's build, with
and without ``[priors]`` at the robot's own values), ``--sessions`` sessions
of each of two plans, simulated and checked as tests/science/slip_sessions.py
does (the Create 2's turns with the fake's e_turn 1.2 % and K_spin 2e-4
rad^2/rad):

* **mixed**: ``k=0.5,l=2,n=8`` (the robot's forth-and-back variant: ``turn``
  on the Nomad, ``reverse`` on the Create 2), ``path=square:0.5,cw,n=8``,
  ``path=square:0.5,ccw,n=8``, each trial predicted under the recipe's fit of
  the trials before it (``PathBeliefEstimator``); then a **validation** of
  ``square:1.0,cw`` and ``circle:0.5,8,ccw``, 8 trials each, predicted under
  the calibration's last estimate (``validate --path``);
* **squares**: ``path=square:1.0,cw,n=10`` (the issue's ``run --plan``).

Counted: clean trials that trip the check (false alarms: re-measured) and
slipped copies caught, with binomial Monte Carlo SE. ``--before``: the belief's
turns as before the fix (exact where no estimate pins them).
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from pathlib import Path

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np  # noqa: E402

from odohil.science.parameters import ErrorParameters  # noqa: E402
from odohil.science.path_designs import PathDesign  # noqa: E402
from odohil.science.paths import Design  # noqa: E402
from tests.science.slip_sessions import (  # noqa: E402
    CREATE2,
    GRID,
    NOMAD,
    PlanItem,
    SimRobot,
    Tally,
    path_session,
)

VALIDATE: list[PlanItem] = [
    (PathDesign("square", 4, 1.0, counter_clockwise=False), 8),
    (PathDesign("circle", 8, 0.5, counter_clockwise=True), 8),
]
SQUARES: list[PlanItem] = [(PathDesign("square", 4, 1.0, counter_clockwise=False), 10)]


def mixed(robot: SimRobot) -> list[PlanItem]:
    """The mixed calibration plan in ``robot``'s forth-and-back variant."""
    return [
        (Design(0.5, 2.0, robot.variant), 8),  # type: ignore[arg-type]
        (PathDesign("square", 4, 0.5, counter_clockwise=False), 8),
        (PathDesign("square", 4, 0.5, counter_clockwise=True), 8),
    ]


def rate(hits: int, total: int) -> str:
    """``p +- SE`` in percent."""
    if total == 0:
        return "-"
    p = hits / total
    return f"{100 * p:.2f} +- {100 * math.sqrt(max(p * (1 - p), 1.0 / total) / total):.2f}"


def cells(tallies: tuple[Tally, Tally, Tally]) -> str:
    """The table's columns of one row's calibration, validation and squares."""
    return " | ".join(
        f"{t.trials} | {rate(t.tripped, t.trials)} | {rate(t.caught, t.trials)}" for t in tallies
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sessions", type=int, default=4)
    parser.add_argument("--seed", type=int, default=31)
    parser.add_argument("--before", action="store_true")
    args = parser.parse_args()
    rng = np.random.default_rng(args.seed)
    start = time.process_time()
    totals = {robot.name: (Tally(), Tally(), Tally()) for robot in (NOMAD, CREATE2)}
    parts = ("mixed plan", "its validation", "squares plan")
    head = [f"{p} {c}" for p in parts for c in ("trials", "false alarms %", "5 mm caught %")]
    columns = ("robot (E_R, E_T, K_theta, K_rho)", "build", "[priors]", *head)
    print("| " + " | ".join(columns) + " |")
    print("|---" * (3 + len(head)) + "|")
    for name, paper in GRID.items():
        truth = ErrorParameters.from_paper_units(*paper)
        for robot in (NOMAD, CREATE2):
            for given in (False, True):
                row = (Tally(), Tally(), Tally())
                for _ in range(args.sessions):
                    calibration = path_session(
                        truth, robot, given, mixed(robot), VALIDATE, rng,
                        unknown_turns=not args.before,
                    )  # fmt: skip
                    squares = path_session(
                        truth, robot, given, SQUARES, [], rng, unknown_turns=not args.before
                    )
                    row[0].add(calibration.calibration)
                    row[1].add(calibration.validation)
                    row[2].add(squares.calibration)
                for total, part in zip(totals[robot.name], row, strict=True):
                    total.add(part)
                given_text = "yes" if given else "no"
                print(f"| {name} | {robot.name} | {given_text} | {cells(row)} |", flush=True)
    for robot_name, sums in totals.items():
        print(f"| all | {robot_name} | | {cells(sums)} |")
    print(f"CPU {time.process_time() - start:.0f} s")


if __name__ == "__main__":
    main()
