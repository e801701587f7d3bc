"""A validation session predicts its trials with the calibration it tests, not
with the robot description's priors nor with an estimate fitted on its own
held-out trials (issue 19's closing note: validation sessions re-measured 0-16
times per cell because their live prediction came from the priors).

The prediction picks the floor-mark solution and drives the slip check; a
validation's trials are tested against the calibration, so that is the belief
they are measured under."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from odohil.science.parameters import ErrorParameters
from odohil.science.pose_selection import ParameterBelief, predictive_pose
from odohil.session.engine import SessionEngine, start_session
from odohil.session.plan import parse_plan
from odohil.session.pose_source import MeasuredPose, MeasurementLog, TrialContext
from odohil.session.sources import TruthPoseSource
from odohil.session.validation import load_calibration
from odohil.session.validation_wizard import guided_validation
from tests.session.helpers import FAST, ROBOT_TOML, fake_robot
from tests.wizard.test_wizard_validation import calibrate


class Recording:
    """The fake's truth channel; keeps the prediction each trial was measured under."""

    def __init__(self, inner: TruthPoseSource) -> None:
        self.inner = inner
        self.seen: list[TrialContext] = []

    def at_start(self, ctx: TrialContext) -> Mapping[str, Any]:
        return self.inner.at_start(ctx)

    def at_end(self, ctx: TrialContext) -> Mapping[str, Any]:
        return self.inner.at_end(ctx)

    def pose_change(self, ctx: TrialContext, log: MeasurementLog) -> MeasuredPose:
        self.seen.append(ctx)
        return self.inner.pose_change(ctx, log)


def test_a_given_belief_predicts_every_trial_and_the_live_estimate_does_not_move_it(
    tmp_path: Path,
) -> None:
    calibrated = ParameterBelief(
        ErrorParameters(e_r=-0.02, e_t=0.01, k_theta=2e-4, k_rho=4e-5),
        np.diag([1e-6, 1e-6, 1e-10, 1e-12]),
        "estimate",
    )
    with fake_robot(f"seed=3&{FAST}") as (robot, truth):
        source = Recording(TruthPoseSource(truth, (0.002, 0.002, 0.004), seed=1))
        journal, state = start_session(
            tmp_path / "v", ROBOT_TOML, parse_plan("k=1,l=1,n=4"), measure="fake", settings={}
        )
        with journal:
            SessionEngine(journal, state, robot, source, belief=calibrated).run()
    assert len(source.seen) == 4
    for ctx in source.seen:
        assert ctx.predicted is not None
        assert ctx.encoder_end_pose is not None
        expected = predictive_pose(ctx.design, calibrated, ctx.encoder_end_pose)
        np.testing.assert_array_equal(ctx.predicted.mean, expected.mean)
        np.testing.assert_array_equal(ctx.predicted.cov, expected.cov)


def test_the_wizards_validation_is_predicted_under_its_calibration(tmp_path: Path) -> None:
    """The session spec of `odohil wizard --validate` carries the calibration's
    estimate, which run_session hands the engine as its belief."""
    session = calibrate(tmp_path)
    guided = guided_validation(session, "square:0.5,cw", 3, port="fakerobot://?seed=1")
    assert guided.spec.calibration is not None
    assert guided.spec.calibration.parameters == load_calibration(session).result.parameters
