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

from odohil.cli.exit_codes import EXIT_OK, EXIT_UNTRUSTED
from odohil.science.parameters import ErrorParameters
from odohil.science.pose_selection import ParameterBelief, predictive_pose
from odohil.session.journal.file import read_journal
from odohil.session.journal.state import load_session
from odohil.session.measure.protocol import MeasuredPose, MeasurementLog, TrialContext
from odohil.session.measure.tape.records import Remeasured
from odohil.session.measure.truth import TruthPoseSource
from odohil.session.plans.plan import parse_plan
from odohil.session.results.validation import load_calibration
from odohil.session.run.engine import SessionEngine, start_session
from odohil.session.run.running import validation_calibration
from odohil.session.wizard.validate import guided_validation
from tests.cli.test_validate_paths import ROBOTS, odohil, robot_option
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


def test_validate_measures_a_driven_path_under_the_calibration(tmp_path: Path) -> None:
    """`odohil validate --port ... --measure fake`: on a fake whose E_R is three
    and K_theta nine times the calibration's, every square disagrees with the
    calibration's prediction, so the slip check asks again (the fake's tape
    re-measures) before the validation fails; under the priors (before) it
    never asked: 0 re-measures in either direction at seed 2."""
    nomad = ROBOTS["nomad150"]
    calibration = tmp_path / "calibration"
    code, _, err = odohil(
        "run", "--allow-few-trials", "--robot", robot_option("nomad150", tmp_path),
        "--port", nomad["url"].format(seed=2), "--plan", nomad["plan"], "--measure", "fake",
        "--seed", "2", "--session", str(calibration), "--json",
    )  # fmt: skip
    assert code == EXIT_OK, err
    folder = tmp_path / "validation"
    code, _, err = odohil(
        "validate", str(calibration), "--port", nomad["url"].format(seed=102) + nomad["wrong"],
        "--path", "square:1.0,cw", "--trials", "15", "--measure", "fake", "--seed", "102",
        "--out", str(folder), "--json",
    )  # fmt: skip
    assert code == EXIT_UNTRUSTED, err
    kinds = [record.kind for record in read_journal(folder).records]
    assert kinds.count(Remeasured.KIND) > 0
    # `odohil resume` of the validation measures under the same calibration:
    # its header names it (validation_of); a calibration session names none
    resumed = validation_calibration(None, load_session(folder).state)
    assert resumed is not None
    assert resumed.parameters == load_calibration(calibration).result.parameters
    assert validation_calibration(None, load_session(calibration).state) is None
