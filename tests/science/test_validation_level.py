"""The validation's false-rejection rate when the calibration is itself an
estimate (issue 31): a calibrated robot passes at the rate alpha promises.

The calibration is drawn from the law of an estimate, not taken as the truth:
each variance rate is a variance estimated from NU squares, K-hat = K
chi^2(NU) / NU, reported with its Wald standard error at the estimate, K-hat
sqrt(2 / NU) (what odohil's estimator gives: over bench/validation_power.py's
100 Nomad calibrations sd(log K-hat) 0.32 / 0.31 against a median relative
SE of 0.30 / 0.29); E_R and E_T are normal around the truth with the standard
errors the test is given. The validation trials are the discrete model's
(odohil/science/simulator.py) on the true robot. Each NEES test, and each
bias test, must reject at most at its level (within 4 Monte Carlo SE).
"""

from __future__ import annotations

import math

import numpy as np

from odohil.science.parameters import ErrorParameters
from odohil.science.paths import square
from odohil.science.simulator import simulate
from odohil.science.validation import N_TESTS, predict_path, validation_test

TRUTH = ErrorParameters.from_paper_units(-0.5, -0.02, 0.1, 1e-4)
MEASUREMENT_COV = np.diag([1e-6, 1e-6, 4e-6])
PATH = square(1.0, counter_clockwise=False)
NU = 12
"""The variance rates' degrees of freedom: relative SE sqrt(2 / 12) = 0.41."""
MEAN_SE = np.array([2e-3, 0.01])
"""E_R rad/m and E_T standard errors."""


def test_a_calibrated_robot_passes_at_the_level_when_the_spread_is_an_estimate() -> None:
    n, sets, alpha = 30, 400, 0.16
    level = alpha / N_TESTS  # 0.02 per test
    rng = np.random.default_rng(31)
    poses = simulate(PATH, TRUTH, sets * n, seed=rng, segment_m=0.004).pose_change
    poses += rng.multivariate_normal(np.zeros(3), MEASUREMENT_COV, size=poses.shape[0])
    covs = np.broadcast_to(MEASUREMENT_COV, (n, 3, 3))
    rejected, verdicts = np.zeros(N_TESTS), 0
    true = np.array(TRUTH.as_tuple())
    for one in poses.reshape(sets, n, 3):
        values = true.copy()
        values[:2] += MEAN_SE * rng.standard_normal(2)
        values[2:] *= rng.chisquare(NU, size=2) / NU
        se = np.concatenate([MEAN_SE, values[2:] * math.sqrt(2 / NU)])
        prediction = predict_path(PATH, ErrorParameters(*values))
        tested = validation_test(one, [prediction] * n, covs, np.diag(se**2), alpha=alpha)
        rejected += [not t.passed for t in tested.tests]
        verdicts += not tested.passed
    rates = rejected / sets
    mc_se = math.sqrt(level * (1 - level) / sets)
    assert verdicts / sets < alpha + 4 * math.sqrt(alpha * (1 - alpha) / sets)
    assert np.all(rates < level + 4 * mc_se), dict(
        zip([t.name for t in tested.tests], rates.round(4), strict=True)
    )
