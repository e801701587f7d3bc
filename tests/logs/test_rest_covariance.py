"""The measured pose change's covariance from the rests' scatter is right,
not merely safe (a covariance too large biases K_theta and K_rho low):
Monte Carlo of synthetic logs with white capture jitter."""

from __future__ import annotations

import numpy as np

from odohil.session.trials.logs.recording import ImportOptions, Recording, trials_of
from tests.logs.data import optiodom_robot
from tests.logs.synth import synth_log, varied_motions

SEEDS = 100
"""400 trials: the standard deviation of a normalised error is known to about
0.035 (1 / sqrt(2 x 400)); the bounds below are 4 of those."""


def test_normalised_errors_of_the_pose_change_have_unit_spread() -> None:
    robot = optiodom_robot()  # no pose_sigma: the rests' scatter
    z = []
    for seed in range(SEEDS):
        log = synth_log(varied_motions(), seed=seed, jitter=(3e-4, 3e-3))
        rec = Recording("s", log.t_s, log.odometry, log.truth, np.arange(len(log.t_s)))
        for trial, true in zip(
            trials_of(rec, robot, ImportOptions()), log.true_changes, strict=True
        ):
            error = trial.pose_change - (np.array(true) - [0.0, 0.0, trial.path.winding_rad])
            z.append(error / np.sqrt(np.diag(trial.measurement_cov)))
    spread = np.array(z).std(axis=0)
    assert len(z) == 4 * SEEDS
    assert np.all(spread > 0.86), spread
    assert np.all(spread < 1.14), spread
    assert np.all(np.abs(np.array(z).mean(axis=0)) < 0.2)
