"""The slip check on clean tape, at corners of the robots issue 31 asks for:
E_R +-2 deg/m, E_T +-5 %, K_theta 1 deg^2/m, K_rho 1e-6 and 1e-3 m, with and
without ``[priors]``, the paper's motion and the Create 2's turn-free one.

Each trial is simulated by the discrete model (odohil/science/simulator.py),
its five distances read with 1 mm Gaussian noise, and predicted as a session
predicts it (odohil/session/run/engine.py): the running incremental estimate
as a belief, the priors (or, without ``[priors]``, the unknown robot's belief)
before there is one. Measured on the code before issue 31 (seed 31): 4 and 12
of 20 clean trials tripped the check at the first two corners (the third,
[priors] at the robot's values, passed before too); the
check's level is 0.001 and bench/slip_check.py measures the rate after the
fix over the grid (BENCHMARKS.md): at a true rate of 0.3 % two trips or more
in 20 happen with probability 0.002.
"""

from __future__ import annotations

import contextlib

import numpy as np
import pytest

from odohil.errors import OdohilError
from odohil.science.estimators import IncrementalEstimator, Observation
from odohil.science.floor_marks import MarkDistances, marks_from_pose
from odohil.science.parameters import ErrorParameters
from odohil.science.paths import Design
from odohil.science.pose_selection import ParameterBelief, predictive_pose, select_pose
from odohil.science.robot_description import ParameterPriors, RobotDescription, Screw
from odohil.science.simulator import simulate

SCREWS = (Screw("A", 0.2, 0.0), Screw("B", -0.1, 0.173), Screw("C", -0.1, -0.173))


def _trips(
    truth: ErrorParameters, priors: ParameterPriors, designs: list[Design], seed: int
) -> int:
    """How many of a session's clean trials (``designs`` in order) trip the check."""
    description = RobotDescription(SCREWS, 0.001, (("A", "B"), ("B", "C")), priors=priors)
    rng = np.random.default_rng(seed)
    estimator = IncrementalEstimator()
    trips = 0
    for trial, design in enumerate(designs, 1):
        pose = simulate(design.path(), truth, 1, seed=rng).pose_change[0]
        exact = marks_from_pose(description, pose).as_array()
        readings = exact + rng.normal(0.0, description.sigma_m, exact.size)
        belief = ParameterBelief.from_priors(priors)
        if estimator.fit is not None:
            with contextlib.suppress(OdohilError):
                belief = ParameterBelief.from_result(estimator.result(), priors)
        odometry = design.path().encoder_end_pose()
        predicted = predictive_pose(design, belief, odometry)
        marks = MarkDistances.of(description, readings)
        selection = select_pose(description, marks, odometry, predicted)
        trips += selection.slip.tripped
        observation = Observation(
            design, selection.solution.pose_change, selection.solution.cov, trial=trial
        )
        with contextlib.suppress(OdohilError):
            estimator.add(observation)
    return trips


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
    priors = ParameterPriors(mean=truth, given=True) if given else ParameterPriors()
    designs = [Design(1, 3, variant)] * 12 + [Design(0.5, 3, variant)] * 8  # type: ignore[arg-type]
    assert _trips(truth, priors, designs, seed=31) <= 1
