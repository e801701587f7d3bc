"""The slip check on clean tape, at corners of the robots issue 31 asks for:
E_R +-2 deg/m, E_T +-5 %, K_theta 1 deg^2/m, K_rho 1e-6 and 1e-3 m, with and
without ``[priors]``, the paper's motion and the Create 2's turn-free one.

Sessions of forth-and-back designs as tests/science/slip_sessions.py
simulates them (``forth_back_session``, also bench/slip_check.py's): the
running incremental estimate as a belief, the priors (or, without
``[priors]``, the unknown robot's belief) before there is one. Measured on
the code before issue 31 (seed 31, this test's loop at 88b0f46: the same
designs, one-way trials not alternated, no slipped copies drawn): 4 and 12 of
20 clean trials tripped the check at the first two corners (the third,
[priors] at the robot's values, passed before too); the check's level is
0.001 and bench/slip_check.py measures the rate after the fix over the grid
(BENCHMARKS.md): at a true rate of 0.3 % two trips or more in 20 happen with
probability 0.002.
"""

from __future__ import annotations

import numpy as np
import pytest

from odohil.science.parameters import ErrorParameters
from tests.science.slip_sessions import NOMAD_SCREWS, SimRobot, forth_back_session


@pytest.mark.parametrize(
    ("paper", "given", "variant"),
    [
        ((-2.0, 0.05, 1.0, 1e-6), False, "turn"),
        ((2.0, -0.05, 1.0, 1e-3), False, "reverse"),
        ((2.0, -0.05, 1.0, 1e-3), True, "reverse"),
    ],
)
def test_clean_trials_of_a_far_robot_rarely_trip(
    paper: tuple[float, float, float, float], given: bool, variant: str
) -> None:
    truth = ErrorParameters.from_paper_units(*paper)
    robot = SimRobot(variant, NOMAD_SCREWS, True, variant=variant)
    plan = ((1.0, 3.0, 12), (0.5, 3.0, 8))
    tally = forth_back_session(truth, robot, given, plan, np.random.default_rng(31))
    assert tally.trials == 20
    assert tally.tripped <= 1, tally.tripped_at
