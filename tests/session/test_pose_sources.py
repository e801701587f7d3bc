"""The session's PoseSources through the engine and the fake robot: a trial
file of poses is read as poses (no round trip through distances), one of raw
distances goes through the tape and the floor-marks solver, and the fake's
truth channel gives the true pose change with seeded noise (issue 10)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from odohil.science.floor_marks import marks_from_pose, pose_covariance
from odohil.session.journal.file import read_journal
from odohil.session.journal.state import SessionState, session_trials
from odohil.session.measure.files import PoseFileSource, pose_source_from_file
from odohil.session.measure.protocol import PoseSource, TrialContext
from odohil.session.measure.tape.records import Measurement
from odohil.session.measure.tape.source import TapeSource
from odohil.session.measure.truth import TruthPoseSource
from odohil.session.plans.plan import parse_plan
from odohil.session.run.engine import SessionEngine, start_session
from tests.session.helpers import FAST, ROBOT_TOML, description, fake_robot, readings_of

QUERY = f"seed=11&{FAST}&E_R=-1.0&E_T=-0.05&K_theta=0.3&K_rho=0.0009"
POSES = [(0.5, 0.001, -0.004), (-0.49, -0.0005, 0.003)]
"""Two trials of k=0.5, l=0.5 m (the second driven backwards: its end lies
behind its start), each within what the encoders and the priors predict (the
engine refuses an implausible pose, odohil/session/measure/plausibility.py)."""


def _start(folder: Path, plan: str) -> tuple[Any, SessionState]:
    return start_session(folder, ROBOT_TOML, parse_plan(plan), measure="fake", settings={})


def _kinds(folder: Path) -> list[str]:
    return [r.kind for r in read_journal(folder).records]


def _run(folder: Path, source: PoseSource, plan: str = "k=0.5,l=0.5,n=2") -> SessionState:
    with fake_robot(QUERY) as (robot, _):
        journal, state = _start(folder, plan)
        with journal:
            return SessionEngine(journal, state, robot, source).run()


def _pose_file(path: Path) -> Path:
    lines = ["k,l_m,variant,dx_m,dy_m,dtheta_rad"]
    for variant, pose in zip(("turn", "turn-backward"), POSES, strict=True):
        lines.append(",".join(str(v) for v in (0.5, 0.5, variant, *pose)))
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def test_a_trial_file_of_poses_is_read_as_poses(tmp_path: Path) -> None:
    source = pose_source_from_file(_pose_file(tmp_path / "poses.csv"), description())
    assert isinstance(source, PoseFileSource)
    final = _run(tmp_path / "s", source)
    for trial, pose in zip(final.completed, POSES, strict=True):
        assert trial.pose_change == pose  # exactly: no distances, no solver
        expected_cov = pose_covariance(description(), pose)
        np.testing.assert_allclose(trial.cov, expected_cov, rtol=1e-12)
        assert trial.readings is None
    assert Measurement.KIND not in _kinds(tmp_path / "s")
    offline = session_trials(final)  # odohil estimate SESSION, the report
    assert [t.marks for t in offline.trials] == [None, None]
    assert [t.flagged for t in offline.trials] == [False, False]


def test_a_trial_file_of_distances_goes_through_the_solver(tmp_path: Path) -> None:
    marks = [marks_from_pose(description(), pose).as_array() for pose in POSES]
    header = "k,l_m,variant,d1_m,d2_m,d3_m,cross1_m,cross2_m"
    rows = [
        ",".join(str(v) for v in (0.5, 0.5, variant, *row))
        for variant, row in zip(("turn", "turn-backward"), marks, strict=True)
    ]
    file = tmp_path / "marks.csv"
    file.write_text("\n".join([header, *rows]) + "\n", encoding="utf-8")
    source = pose_source_from_file(file, description())
    assert isinstance(source, TapeSource)
    final = _run(tmp_path / "s", source)
    for trial, pose in zip(final.completed, POSES, strict=True):
        np.testing.assert_allclose(trial.pose_change, pose, atol=1e-7)
        assert len(readings_of(trial)) == 5
    assert _kinds(tmp_path / "s").count(Measurement.KIND) == 2 * 5


def test_the_fakes_truth_channel_is_a_pose_source_that_resumes_alike(tmp_path: Path) -> None:
    sigma = (0.002, 0.002, 0.004)
    plan = "k=1,l=0.5,n=3"
    with fake_robot(QUERY) as (robot, truth):
        journal, state = _start(tmp_path / "s", plan)
        with journal:
            final = SessionEngine(
                journal, state, robot, TruthPoseSource(truth, sigma, seed=5)
            ).run()
    assert len(final.completed) == 3
    for trial in final.completed:
        start, end = np.array(trial.start["true_pose"]), np.array(trial.end["true_pose"])
        c, s = np.cos(start[2]), np.sin(start[2])
        dx, dy = end[:2] - start[:2]
        winding = trial.design.path().winding_rad  # the full turns the design makes
        true = np.array([c * dx + s * dy, -s * dx + c * dy, end[2] - start[2] - winding])
        assert np.all(np.abs(np.array(trial.pose_change) - true) < 5 * np.array(sigma))
        np.testing.assert_allclose(np.diag(trial.cov), np.square(sigma))
    # the noise is seeded by (seed, trial, attempt): given the journaled true
    # poses, a resumed session measures exactly what the first one did
    again = TruthPoseSource(truth, sigma, seed=5)
    for trial in final.completed:
        ctx = TrialContext(trial.trial, trial.attempt, 3, trial.design, trial.start, trial.end)
        assert again.pose_change(ctx, _no_log).pose == trial.pose_change


def _no_log(kind: str, data: Any) -> Any:
    raise AssertionError("the truth channel journals no intermediate readings")
