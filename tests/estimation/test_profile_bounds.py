"""The profile-likelihood bounds of the general-path fit against a brute-force
profile (odohil/science/estimators/intervals.py, issue 20's speed work).

The profile deviance of log K = psi is D(psi) = 2 [min over the other
parameters of NLL_CR(psi, .) - NLL_CR(estimate)], NLL_CR the Cox-Reid adjusted
NLL as the interval code defines it (the model's derivatives held at the
estimate, so the adjustment is the one the fit solved). Here the minimum is
found by brute force (scipy's Powell, from the estimate, in units of the
standard errors: a Nelder-Mead polish and a tighter tolerance move the root
by less than 1e-8), independently of the interval code's own search, and
each bound the code returns must sit where the brute-force signed root
sqrt(D) reaches the level q (1.96 at 95 %, 4 at the 4-sigma level) to within
ROOT_TOLERANCE (the code's own stopping rule is 0.01; the rest is the brute
force's slack). An open bound (0 below) must be one the deviance never
reaches: the brute-force root at the floor of log K stays below q.

Data: 30 simulated trials of random 12-leg paths with spins and arc turns
(as bench/path_fit_speed.py's), whose K_rho the data put at the floor (the
motion-capture noise hides it, as on the optiodom runs: K_rho ~ 0), and
K_theta and K_spin in the interior.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import optimize

from odohil.science.diff_drive import simulate_turn_errors
from odohil.science.estimators.intervals import FOUR_SIGMA, profile_interval
from odohil.science.estimators.joint import JointFit, designs_of
from odohil.science.estimators.likelihood import GroupStats, evaluate, with_moments
from odohil.science.estimators.paths import fit_paths, path_groups
from odohil.science.moments import TurnErrors
from odohil.science.parameters import ErrorParameters
from odohil.science.path_trials import PathTrial
from odohil.science.paths import EncoderPath, Leg, Step, Turn

TRUTH = ErrorParameters.from_paper_units(-0.5, -0.003, 0.2, 4e-7)
TURNS = TurnErrors(-0.007, -0.007, -0.012, -0.012, k_spin=1e-4)
MEASUREMENT = np.diag([1e-8, 1e-8, 1e-6])
LOG_K_RANGE = (math.log(1e-14), math.log(1e2))
Q95 = 1.959963984540054
ROOT_TOLERANCE = 0.03
"""|brute-force signed root at a bound - q| allowed (root units: 0.03 at
q = 1.96 is 3 % of the deviance, a few thousandths of log K here)."""


def _path(rng: np.random.Generator, legs: int) -> EncoderPath:
    steps: list[Step] = []
    for i in range(legs):
        steps.append(Leg(float(rng.uniform(0.1, 0.4)) * (1.0 if rng.random() < 0.85 else -1.0)))
        if i < legs - 1:
            if rng.random() < 0.3:
                steps.append(Turn(float(rng.uniform(-math.pi / 2, math.pi / 2)), "spin"))
            else:
                steps.append(Turn(float(rng.uniform(-0.35, 0.35)), "arc"))
    return EncoderPath(tuple(steps), name="random")


def _trials(n: int, legs: int, seed: int) -> list[PathTrial]:
    rng = np.random.default_rng(seed)
    out = []
    for i in range(n):
        path = _path(rng, legs)
        pose = simulate_turn_errors(path, TRUTH, TURNS, 1, seed=rng, segment_m=0.01).pose_change[0]
        pose = pose + rng.multivariate_normal(np.zeros(3), MEASUREMENT)
        out.append(PathTrial(path, pose, MEASUREMENT, trial=i + 1, family="random"))
    return out


class _Brute:
    """The brute-force profile NLL of one fit."""

    def __init__(self, groups: list[GroupStats], fit: JointFit) -> None:
        self.groups = groups
        self.fit = fit
        self.keys = designs_of(groups)
        self.model = fit.point.model
        self.anchor = self.model.point(fit.point.phi, self.keys, derivatives=True)
        assert fit.value.information is not None
        se = np.sqrt(np.diag(np.linalg.inv(fit.value.information)))
        self.scale = np.where(np.isfinite(se) & (se > 0) & (se < 5.0), se, 1.0)
        self.reference = self.nll(fit.point.phi)

    def nll(self, phi: np.ndarray) -> float:
        point = with_moments(self.anchor, self.model.point(phi, self.keys, derivatives=False))
        return evaluate(self.groups, point, cox_reid=True).nll

    def root(self, index: int, psi: float) -> float:
        """sign(psi - psi_hat) sqrt(D(psi)), the minimum by brute force."""
        layout = self.fit.point.layout
        free = [i for i in range(layout.size) if i != index]
        base = self.fit.point.phi.copy()
        base[index] = psi

        def f(u: np.ndarray) -> float:
            phi = base.copy()
            phi[free] += u * self.scale[free]
            return self.nll(layout.bounded(phi, *LOG_K_RANGE))

        powell = optimize.minimize(
            f, np.zeros(len(free)), method="Powell", options={"xtol": 1e-3, "ftol": 1e-10}
        )
        deviance = max(0.0, 2.0 * (float(powell.fun) - self.reference))
        return math.copysign(math.sqrt(deviance), psi - float(self.fit.point.phi[index]))


@pytest.fixture(scope="module")
def brute() -> _Brute:
    trials = _trials(30, 12, seed=2)
    fit = fit_paths(trials, turns_exact=False)
    return _Brute(path_groups(trials), fit)


def test_the_data_put_k_rho_at_the_floor_and_k_theta_inside(brute: _Brute) -> None:
    names = brute.fit.point.layout.names
    phi = brute.fit.point.phi
    assert phi[names.index("K_rho")] <= LOG_K_RANGE[0] + 1e-9
    assert LOG_K_RANGE[0] + 5 < phi[names.index("K_theta")] < LOG_K_RANGE[1]
    assert LOG_K_RANGE[0] + 5 < phi[names.index("K_spin")] < LOG_K_RANGE[1]


@pytest.mark.parametrize("name", ["K_theta", "K_rho", "K_spin"])
def test_profile_bounds_agree_with_a_brute_force_profile(brute: _Brute, name: str) -> None:
    index = brute.fit.point.layout.names.index(name)
    interval = profile_interval(brute.groups, brute.fit, index)
    for q, (low, high) in ((Q95, interval.ci95), (FOUR_SIGMA, interval.ci_4sigma)):
        if low > 0:
            assert brute.root(index, math.log(low)) == pytest.approx(-q, abs=ROOT_TOLERANCE)
        else:  # open below: the deviance stays under the level down to the floor
            assert brute.root(index, LOG_K_RANGE[0]) > -q
        assert math.isfinite(high)
        assert brute.root(index, math.log(high)) == pytest.approx(q, abs=ROOT_TOLERANCE)
