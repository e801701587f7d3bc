"""Benchmark: the slip check on clean tape and on a 5 mm slip, over robots far
from the paper's Nomad (issue 31).

Usage: ``nice -n 10 python bench/slip_check.py [--sessions 8] [--seed 31]``

Each session is the issue's plan (k=1 l=3 n=15; k=5 l=1 n=15; k=0.5 l=3
n=10, one-way trials alternating direction as a session drives them) on a
robot of the grid, with the paper's motion (``turn``, the Nomad) or the
Create 2's turn-free one (``reverse``), with and without ``[priors]`` (given:
the robot's own values with the default deviations). Each trial is
simulated, predicted (the running incremental estimate as a belief, the
priors before there is one) and checked as tests/science/slip_sessions.py
``forth_back_session`` does. Counted per cell: the **false-alarm rate**
(clean trials that trip the check, i.e. would be re-measured) and the
**catch rate** of a 5 mm slip (the same readings with one distance, chosen at
random, off by +-5 mm), each with its binomial Monte Carlo SE. The estimate
is fed the clean trial. Forth-and-back paths only: general paths,
and the Create 2's build, are bench/slip_check_paths.py's.
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
from tests.science.slip_sessions import (  # noqa: E402
    GRID,
    NOMAD_SCREWS,
    SimRobot,
    forth_back_session,
)

PLAN = ((1.0, 3.0, 15), (5.0, 1.0, 15), (0.5, 3.0, 10))
MOTIONS = {  # the Nomad's screws and exact turns, in either motion
    variant: SimRobot(variant, NOMAD_SCREWS, True, variant=variant)
    for variant in ("turn", "reverse")
}


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
    for name, paper in GRID.items():
        truth = ErrorParameters.from_paper_units(*paper)
        for variant in ("turn", "reverse"):
            for given in (False, True):
                cell = [0, 0, 0]
                for _ in range(args.sessions):
                    tally = forth_back_session(truth, MOTIONS[variant], given, PLAN, rng)
                    for i, v in enumerate((tally.trials, tally.tripped, tally.caught)):
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
