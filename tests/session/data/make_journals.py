"""Writes the journals of tests/session/data/journals/ (run once, with the code of
the day they were made; kept so that every later odohil must replay them alike).

    PYTHONPATH=$PWD python tests/session/data/make_journals.py

Each journal was written by the engine against the in-process fake robot
(fakerobot://); ``expected.json`` beside them holds what that day's code
replayed them to (tests/session/test_old_journals.py compares).
"""

from __future__ import annotations

import json
import shutil
import sys
from pathlib import Path
from typing import Any

import pytest
import serial

import fakes  # noqa: F401  (registers fakerobot://)
from odohil.driver.nomad.backend import NomadBackend
from odohil.science.floor_marks import marks_from_pose
from odohil.science.robot_description import RobotDescription
from odohil.session.journal.file import Record
from odohil.session.journal.state import SessionState
from odohil.session.measure.protocol import TrialContext
from odohil.session.measure.tape.distances import FakeTruthSource, OperatorSource
from odohil.session.measure.truth import TruthPoseSource, relative_true_pose
from odohil.session.plans.plan import parse_plan
from odohil.session.run.engine import (
    CallbackObserver,
    IncrementalLiveEstimator,
    MotionSettings,
    SessionEngine,
    description_of,
    resume_session,
    start_session,
)
from tests.report.session_factory import PortTruth
from tests.session.helpers import ROBOT_TOML

HERE = Path(__file__).resolve().parent / "journals"
NO_CROSS_TOML = ROBOT_TOML.replace('cross = [["A", "B"], ["B", "C"]]\n', "")
MOTION = MotionSettings(speeds=(1.0, 3.0), accelerations=(2.0, 6.0), watchdog_s=0.0)
QUERY = "seed={seed}&time_scale=2000&E_R=-1.0&E_T=-0.05&K_theta=0.3&K_rho=0.0009"


def _robot(seed: int) -> tuple[NomadBackend, Any]:
    port = serial.serial_for_url(f"fakerobot://?{QUERY.format(seed=seed)}", timeout=0.5)
    return NomadBackend.from_port(port), port


class TapeOperator:
    """An operator (the wizard's side of OperatorPrompts) with a tape: reads
    the fake's true pose at the marks, answers with the exact distance plus a
    little noise; on trial 1 misreads distance 0 by 5 cm the first time (a
    rejection); from trial 2 on types distance ``trial % 5`` 6 mm long the
    first time (rejected, or caught by the slip check: re-measured, or kept on
    trial 6)."""

    def __init__(self, port: serial.Serial, description: RobotDescription) -> None:
        self.truth = PortTruth(port)
        self.description = description
        self.start = (0.0, 0.0, 0.0)
        self.change = (0.0, 0.0, 0.0)

    def confirm_start_marks(self, ctx: TrialContext) -> None:
        self.start = self.truth.true_pose()

    def confirm_end_marks(self, ctx: TrialContext) -> None:
        self.change = relative_true_pose(
            self.start, self.truth.true_pose(), ctx.design.path().winding_rad
        )

    def _exact(self, index: int) -> float:
        return round(float(marks_from_pose(self.description, self.change).as_array()[index]), 4)

    def ask_distance(self, ctx: TrialContext, index: int) -> float:
        value = self._exact(index)
        if ctx.trial == 1 and ctx.rejections == 0 and index == 0:
            return value + 0.05
        if ctx.trial >= 2 and ctx.rejections == 0 and index == ctx.trial % 5:
            return value + 0.006
        return value

    def show_rejection(self, ctx: TrialContext, reason: str) -> None:
        pass

    def ask_remeasure(self, ctx: TrialContext, index: int, reason: str) -> float | None:
        return None if ctx.trial == 6 else self._exact(index)

    def ask_extra_distance(self, ctx: TrialContext, label: str, reason: str) -> float | None:
        return None


class ExtraOperator(TapeOperator):
    """Exact distances; answers an ambiguous trial's extra distance."""

    def ask_distance(self, ctx: TrialContext, index: int) -> float:
        return self._exact(index)

    def ask_extra_distance(self, ctx: TrialContext, label: str, reason: str) -> float | None:
        from dataclasses import replace

        start, end = label.replace(" start to ", " ").replace(" end", "").split()
        probe = replace(self.description, cross_pairs=((start, end),))
        return marks_from_pose(probe, self.change).cross_m[0]


class FailingAt(FakeTruthSource):
    """Breaks off (as Ctrl-C would) when asked for distance ``index`` of ``trial``."""

    def __init__(self, *args: Any, trial: int, index: int, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.at = (trial, index)

    def distance(self, ctx: TrialContext, index: int) -> float:
        if (ctx.trial, index) == self.at:
            raise KeyboardInterrupt
        return super().distance(ctx, index)


def _interrupt_on(kind: str, trial: int) -> CallbackObserver:
    def callback(record: Record, state: SessionState) -> None:
        if record.kind == kind and record.data.get("trial") == trial:
            raise KeyboardInterrupt

    return CallbackObserver(callback)


def finished(folder: Path) -> None:
    journal, state = start_session(
        folder, ROBOT_TOML, parse_plan("k=1,l=1,n=3;k=0.5,l=1.5,n=3"), measure="fake",
        settings={"seed": 3},
    )  # fmt: skip
    robot, port = _robot(11)
    with journal, robot:
        source = FakeTruthSource(PortTruth(port), description_of(state), seed=3)
        SessionEngine(
            journal, state, robot, source, estimator=IncrementalLiveEstimator(), motion=MOTION
        ).run()


def interrupted(folder: Path) -> None:
    journal, state = start_session(
        folder, ROBOT_TOML, parse_plan("k=1,l=0.5,n=4"), measure="fake", settings={"seed": 3}
    )
    robot, port = _robot(12)
    with robot:
        truth = PortTruth(port)
        with journal, pytest.raises(KeyboardInterrupt):
            SessionEngine(
                journal, state, robot, FakeTruthSource(truth, description_of(state), seed=3),
                estimator=IncrementalLiveEstimator(), motion=MOTION,
                observer=_interrupt_on("motion_start", 2),
            ).run()  # fmt: skip
        resumed = resume_session(folder, {"by": "make_journals"})
        failing = FailingAt(truth, description_of(state), seed=3, trial=3, index=2)
        with resumed.journal, pytest.raises(KeyboardInterrupt):
            SessionEngine(
                resumed.journal, resumed.state, robot, failing,
                estimator=IncrementalLiveEstimator(), motion=MOTION,
            ).run()  # fmt: skip


def wizard(folder: Path) -> None:
    journal, state = start_session(
        folder, ROBOT_TOML, parse_plan("k=1,l=1,n=3;k=4,l=0.5,n=3"), measure="operator",
        settings={"port": "fakerobot://?seed=7"},
    )  # fmt: skip
    robot, port = _robot(7)
    with journal, robot:
        operator = TapeOperator(port, description_of(state))
        SessionEngine(
            journal, state, robot, OperatorSource(operator),
            estimator=IncrementalLiveEstimator(), motion=MOTION,
        ).run()  # fmt: skip


def extra(folder: Path) -> None:
    journal, state = start_session(
        folder, NO_CROSS_TOML, parse_plan("k=1,l=1,n=4"), measure="operator", settings={}
    )
    robot, port = _robot(4)
    with journal, robot:
        operator = ExtraOperator(port, description_of(state))
        SessionEngine(
            journal, state, robot, OperatorSource(operator),
            estimator=IncrementalLiveEstimator(), motion=MOTION,
        ).run()  # fmt: skip


def truth_poses(folder: Path) -> None:
    journal, state = start_session(
        folder, ROBOT_TOML, parse_plan("k=1,l=1,n=2;k=0.5,l=1,n=2"), measure="fake", settings={}
    )
    robot, port = _robot(5)
    with journal, robot:
        source = TruthPoseSource(PortTruth(port), (0.001, 0.001, 0.002), seed=5)
        SessionEngine(
            journal, state, robot, source, estimator=IncrementalLiveEstimator(), motion=MOTION
        ).run()


SESSIONS = {
    "finished": finished,
    "interrupted": interrupted,
    "wizard": wizard,
    "extra": extra,
    "truth_poses": truth_poses,
}


def main() -> None:
    sys.path.insert(0, str(Path(__file__).resolve().parents[3]))
    from tests.session.test_old_journals import snapshot

    if HERE.exists():
        shutil.rmtree(HERE)
    HERE.mkdir(parents=True)
    expected: dict[str, Any] = {}
    for name, write in SESSIONS.items():
        write(HERE / name)
        for extra_file in (HERE / name).iterdir():
            if extra_file.name != "journal.jsonl":
                extra_file.unlink()
        expected[name] = snapshot(HERE / name)
    (HERE / "expected.json").write_text(json.dumps(expected, indent=1) + "\n", encoding="utf-8")


if __name__ == "__main__":
    main()
