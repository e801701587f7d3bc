"""The Satterthwaite degrees of freedom of the mean parameters when a variance
rate sits on its floor (odohil/science/estimators/intervals.py, _rate_step).

A Create 2 calibration (issue 19's bench, seed 4: K_theta fitted at 1e-14
rad^2/m) gave E_T nu = 1.0, a 95 % interval of 12.7 standard errors and a
4-sigma one of +-14, and its export was refused as imprecise: the derivative
of SE^2 in log K_theta was round-off (a step of 0.05 in log K moves K by
1e-15) times Var(log K) = 3.5e17. E_T's standard error does not depend on
K_theta there, so its degrees of freedom must rest on the other rates.
"""

from __future__ import annotations

import numpy as np
import pytest

from odohil.science.diff_drive import simulate_turn_errors
from odohil.science.estimators.paths import estimate_paths
from odohil.science.moments import TurnErrors
from odohil.science.parameters import ErrorParameters
from odohil.science.path_trials import PathTrial
from odohil.science.paths import EncoderPath, Leg, Turn

TRUTH = ErrorParameters.from_paper_units(-0.35, -0.015, 0.0, 5e-5)
"""The fake Create 2's errors with no heading noise on straight legs: K_theta's
fit lands on its floor."""
TURNS = TurnErrors(0.012, 0.012, 0.012, 0.012, k_spin=2e-4)
MEASUREMENT = np.diag([0.3e-3**2, 0.3e-3**2, 0.05e-3**2])


def _square(ccw: bool) -> EncoderPath:
    turn = Turn((1 if ccw else -1) * np.pi / 2, "spin")
    return EncoderPath((Leg(0.5), turn) * 4, name="square")


def _trials(seed: int) -> list[PathTrial]:
    rng = np.random.default_rng(seed)
    plan = [
        (EncoderPath((Leg(2.0), Leg(-2.0)), name="reverse"), "mixed", 10),
        (_square(False), "cw", 25),
        (_square(True), "ccw", 25),
    ]
    out = []
    for path, direction, n in plan:
        poses = simulate_turn_errors(path, TRUTH, TURNS, n, seed=rng, segment_m=0.005)
        for pose in poses.pose_change:
            noisy = pose + rng.multivariate_normal(np.zeros(3), MEASUREMENT)
            out.append(PathTrial(path, noisy, MEASUREMENT, family=path.name, direction=direction))  # type: ignore[arg-type]
    return out


@pytest.mark.parametrize("seed", [4, 5])
def test_a_rate_on_its_floor_leaves_the_mean_parameters_their_degrees_of_freedom(
    seed: int,
) -> None:
    result = estimate_paths(_trials(seed), turns_exact=False, method="joint")
    k_theta = result.parameter("K_theta")
    assert k_theta.value < 1e-12, k_theta  # on its floor: the case
    for name in ("E_R", "E_T", "e_turn"):
        p = result.parameter(name)
        assert p.dof is not None
        # 60 trials: nothing like the 1 to 5 degrees of freedom of the round-off
        assert p.dof > 10, (name, p.dof)
        half = (p.ci95[1] - p.ci95[0]) / 2
        assert half < 2.25 * p.stderr, (name, half / p.stderr)
