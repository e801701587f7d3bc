"""The one pose-selection path in a real session (engine against fakerobot://):
ambiguous trials are journaled, left out of every estimate and listed; an
operator's slip is caught and the suspect distance re-measured.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Mapping
from dataclasses import replace
from pathlib import Path
from typing import Any

import serial

import fakes  # noqa: F401  (registers fakerobot://)
from odohil.driver.nomad.backend import NomadBackend
from odohil.science.floor_marks import marks_from_pose
from odohil.science.robot_description import RobotDescription
from odohil.session.journal import events as ev
from odohil.session.journal.file import read_journal
from odohil.session.journal.state import (
    SessionState,
    ambiguous_trials,
    replay,
    session_observations,
    session_trials,
)
from odohil.session.measure.protocol import TrialContext
from odohil.session.measure.tape.distances import (
    FakeTruthSource,
    MeasurementSource,
    OperatorSource,
)
from odohil.session.measure.tape.records import (
    ExtraDistance,
    MeasurementsRejected,
    Remeasured,
    TapeContext,
)
from odohil.session.measure.tape.source import TapeSource
from odohil.session.measure.truth import relative_true_pose
from odohil.session.plans.plan import parse_plan
from odohil.session.run.engine import (
    IncrementalLiveEstimator,
    MotionSettings,
    SessionEngine,
    description_of,
    start_session,
)
from tests import forked
from tests.report.session_factory import PortTruth
from tests.session.helpers import ROBOT_TOML, readings_of

NO_CROSS_TOML = ROBOT_TOML.replace('cross = [["A", "B"], ["B", "C"]]\n', "")
TYPO_M = 0.01


class TypingSlips(FakeTruthSource):
    """The fake's tape readings, but from trial ``first`` on the operator types
    distance ``trial % m`` 10 mm too long on the first reading of the attempt
    (a re-measure, or the set taken again after a rejection, is typed right)."""

    def __init__(self, *args: Any, first: int, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.first = first
        self.slipped: dict[int, int] = {}

    def distance(self, ctx: TapeContext, index: int) -> float:
        value = super().distance(ctx, index)
        slip = ctx.trial >= self.first and ctx.rejections == 0
        if slip and index == ctx.trial % len(ctx.labels):
            self.slipped[ctx.trial] = index
            return value + TYPO_M
        return value


def _run(
    folder: Path,
    toml: str,
    plan_text: str,
    seed: int,
    make_source: Any = None,
) -> tuple[SessionState, MeasurementSource]:
    plan = parse_plan(plan_text)
    journal, state = start_session(folder, toml, plan, measure="fake", settings={})
    port = serial.serial_for_url(f"fakerobot://?seed={seed}&time_scale=2000", timeout=0.5)
    with journal, NomadBackend.from_port(port) as robot:
        description: RobotDescription = description_of(state)
        source = (make_source or FakeTruthSource)(PortTruth(port), description, seed=seed)
        engine = SessionEngine(
            journal,
            state,
            robot,
            TapeSource(source, description),
            estimator=IncrementalLiveEstimator(),
            motion=MotionSettings(speeds=(1.0, 3.0), accelerations=(2.0, 6.0), watchdog_s=0.0),
        )
        return engine.run(), source


def _records(folder: Path, kind: str) -> list[Mapping[str, Any]]:
    return [r.data for r in read_journal(folder).records if r.kind == kind]


def test_ambiguous_trials_are_journaled_left_out_and_listed(tmp_path: Path) -> None:
    """Without cross distances a closed trial's motion and its inverse leave the
    same marks and the prediction sits between them: ambiguous (pre-flight
    would refuse this robot; the engine must still be honest)."""
    folder = tmp_path / "s"
    state, _ = _run(folder, NO_CROSS_TOML, "k=1,l=1,n=8", seed=4)
    solved = _records(folder, ev.SOLVED)
    flagged = [d for d in solved if d.get("ambiguous")]
    assert flagged, "expected ambiguous trials without cross distances"
    for data in flagged:
        assert len(data["candidates"]) >= 2
    replayed = replay(read_journal(folder).records)
    left_out = ambiguous_trials(replayed)
    assert [t.trial for t in left_out] == [d["trial"] for d in flagged]
    trials = session_trials(replayed)
    assert len(trials.trials) + len(trials.ambiguous) == len(state.completed)
    assert len(session_observations(replayed)) == len(state.completed) - len(left_out)
    estimates = _records(folder, ev.ESTIMATE)
    assert all(e["n_trials"] <= len(state.completed) for e in estimates)

    done = forked.completed(["odohil", "estimate", str(folder), "--json"], env=dict(os.environ))
    assert done.returncode == 3, "ambiguous trials left out make the verdict doubtful"
    result = json.loads(done.stdout)
    assert result["ambiguous_trials"] == [t.trial for t in left_out]
    assert result["n_trials"] == len(state.completed) - len(left_out)


def test_a_slip_is_remeasured_and_journaled(tmp_path: Path) -> None:
    """From trial 5 on every trial has one distance typed 10 mm long. Each is
    either refused as inconsistent (the old check) or caught by the slip check,
    which names the typed distance and re-measures just that one."""
    folder = tmp_path / "s"

    def source(*args: Any, **kwargs: Any) -> TypingSlips:
        return TypingSlips(*args, first=5, **kwargs)

    state, used = _run(folder, ROBOT_TOML, "k=1,l=2,n=6;k=4,l=0.5,n=6", seed=7, make_source=source)
    assert isinstance(used, TypingSlips)
    remeasured = _records(folder, Remeasured.KIND)
    assert remeasured, "no slip was caught"
    for data in remeasured:
        assert data["index"] == used.slipped[data["trial"]]
        assert not data["kept"]
        assert data["value_m"] != data["previous_m"]
        assert data["label"] in data["reason"]
    by_trial = {t.trial: t for t in state.completed}
    for data in remeasured:
        trial = by_trial[data["trial"]]
        assert readings_of(trial)[data["index"]] == data["value_m"]
    caught = {d["trial"] for d in remeasured} | {
        d["trial"] for d in _records(folder, MeasurementsRejected.KIND)
    }
    passed = [t for t in state.completed if t.trial >= 5 and t.trial not in caught]
    # a typo that neither check catches must leave the pose within 4 sd
    for t in passed:
        truth = FakeTruthSource.true_pose_change  # the fake's truth, journaled
        ctx = TrialContext(t.trial, t.attempt, 12, t.design, t.start, t.end)
        true = truth(used, ctx)
        sd = t.cov[2][2] ** 0.5
        error = abs(math.remainder(t.pose_change[2] - true[2], 2 * math.pi))
        assert error <= 4 * sd, (t.trial, error / sd)


class TapeOperator:
    """An operator with a perfect tape: reads the fake's true pose at the marks
    and answers every prompt with the exact distance (the user's side of
    :class:`OperatorPrompts`)."""

    def __init__(self, port: serial.Serial, description: RobotDescription) -> None:
        self.truth = PortTruth(port)
        self.description = description
        self.start: tuple[float, float, float] = (0.0, 0.0, 0.0)
        self.change: tuple[float, float, float] = (0.0, 0.0, 0.0)
        self.extra_labels: list[str] = []
        self.truths: dict[int, tuple[float, float, float]] = {}

    def confirm_start_marks(self, ctx: TapeContext) -> None:
        self.start = self.truth.true_pose()

    def confirm_end_marks(self, ctx: TapeContext) -> None:
        self.change = relative_true_pose(
            self.start, self.truth.true_pose(), ctx.design.path().winding_rad
        )
        self.truths[ctx.trial] = self.change

    def ask_distance(self, ctx: TapeContext, index: int) -> float:
        return float(marks_from_pose(self.description, self.change).as_array()[index])

    def show_rejection(self, ctx: TapeContext, reason: str) -> None:
        raise AssertionError(f"exact distances rejected: {reason}")

    def ask_remeasure(self, ctx: TapeContext, index: int, reason: str) -> float | None:
        return self.ask_distance(ctx, index)

    def ask_extra_distance(self, ctx: TapeContext, label: str, reason: str) -> float | None:
        self.extra_labels.append(label)
        start, end = label.replace(" start to ", " ").replace(" end", "").split()
        probe = replace(self.description, cross_pairs=((start, end),))
        return marks_from_pose(probe, self.change).cross_m[0]


def test_the_operator_settles_an_ambiguous_trial_with_one_more_named_distance(
    tmp_path: Path,
) -> None:
    """Without cross distances closed trials are ambiguous; the operator is
    asked for one more distance named by its screws; a trial it settles is
    solved to the true pose and used (one that even the extra distance cannot
    settle, a motion of a few millimetres, stays left out)."""
    folder = tmp_path / "s"
    plan = parse_plan("k=1,l=1,n=4")
    journal, state = start_session(folder, NO_CROSS_TOML, plan, measure="operator", settings={})
    port = serial.serial_for_url("fakerobot://?seed=4&time_scale=2000", timeout=0.5)
    with journal, NomadBackend.from_port(port) as robot:
        operator = TapeOperator(port, description_of(state))
        engine = SessionEngine(
            journal,
            state,
            robot,
            TapeSource(OperatorSource(operator), description_of(state)),
            estimator=IncrementalLiveEstimator(),
            motion=MotionSettings(speeds=(1.0, 3.0), accelerations=(2.0, 6.0), watchdog_s=0.0),
        )
        final = engine.run()
    extra = _records(folder, ExtraDistance.KIND)
    assert extra, "no ambiguous trial was met"
    assert operator.extra_labels == [d["label"] for d in extra]
    for data in extra:
        assert data["label"] == f"{data['start']} start to {data['end']} end"
    asked = {d["trial"] for d in extra}
    settled = [t for t in final.completed if t.trial in asked and not t.ambiguous]
    assert settled
    for trial in settled:
        truth = operator.truths[trial.trial]
        for axis in range(3):
            error = abs(trial.pose_change[axis] - truth[axis])
            assert error <= 5 * trial.cov[axis][axis] ** 0.5 + 1e-9, (trial.trial, axis)
    assert {t.trial for t in ambiguous_trials(final)} <= asked
