"""The session engine against the in-process fake robot (fakerobot://)."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from odohil.driver.odometry import OdometrySample
from odohil.errors import MeasurementError
from odohil.science.estimators import EstimateResult
from odohil.science.floor_marks import marks_from_pose
from odohil.session.journal import events as ev
from odohil.session.journal.file import Record, read_journal
from odohil.session.journal.state import Phase, SessionState, load_session_trials, replay
from odohil.session.measure.protocol import TrialContext
from odohil.session.measure.tape.distances import (
    FakeTruthSource,
    MeasurementSource,
    OperatorSource,
    recorded_source_from_file,
)
from odohil.session.measure.tape.records import Measurement, MeasurementsRejected, TapeContext
from odohil.session.measure.tape.source import TapeSource, check_distance
from odohil.session.measure.truth import relative_true_pose
from odohil.session.plans.plan import parse_plan
from odohil.session.run.engine import (
    CallbackObserver,
    IncrementalLiveEstimator,
    SessionEngine,
    resume_session,
    start_session,
)
from odohil.session.wizard.tape_entry import parse_metres
from tests.session.helpers import FAST, ROBOT_TOML, PortTruth, description, fake_robot

PLAN = "k=1,l=1,n=3;k=0.5,l=1.5,n=3"
# exaggerated errors so that the solved poses differ visibly from the odometry
QUERY = f"seed=11&{FAST}&E_R=-1.0&E_T=-0.05&K_theta=0.3&K_rho=0.0009"


def _start(folder: Path, plan: str = PLAN) -> tuple[Any, SessionState]:
    return start_session(folder, ROBOT_TOML, parse_plan(plan), measure="fake", settings={})


def _kinds(folder: Path) -> list[str]:
    return [r.kind for r in read_journal(folder).records]


def _tape(distances: MeasurementSource) -> TapeSource:
    """The tape and the floor-marks solver over ``distances``."""
    return TapeSource(distances, description())


def test_every_trial_once_with_the_true_pose_change(tmp_path: Path) -> None:
    with fake_robot(QUERY) as (robot, truth):
        journal, state = _start(tmp_path)
        source = FakeTruthSource(truth, description(), seed=3)
        with journal:
            engine = SessionEngine(
                journal, state, robot, _tape(source), estimator=IncrementalLiveEstimator()
            )
            final = engine.run()
    assert final.finished
    assert [t.trial for t in final.completed] == [1, 2, 3, 4, 5, 6]
    assert all(t.attempt == 1 for t in final.completed)
    for t in final.completed:
        ctx = TrialContext(t.trial, t.attempt, 6, t.design, start=t.start, end=t.end)
        true = np.array(source.true_pose_change(ctx))
        solved = np.array(t.pose_change)
        sd = np.sqrt(np.diag(np.array(t.cov)))
        # the floor-mark solution is the truth within its own (5 sigma) error
        assert np.all(np.abs(solved - true) <= 5 * sd + 1e-6), (t.trial, solved, true, sd)
        # odometry reports the commanded path (within one wire unit, 2.54 mm)
        nominal = t.design.path().encoder_end_pose()
        assert np.allclose(t.encoder_end_pose[:2], nominal[:2], atol=0.003)
        assert abs(math.remainder(t.encoder_end_pose[2], 2 * math.pi)) < 0.002
    # the journal on disk tells exactly the same session
    on_disk = replay(read_journal(tmp_path).records)
    assert on_disk.completed == final.completed
    assert on_disk.last_estimate is not None
    assert on_disk.last_estimate.n_trials == 6
    assert on_disk.last_estimate.result is not None
    assert on_disk.last_estimate.result["n_trials"] == 6
    trials = load_session_trials(tmp_path)
    assert [t.line for t in trials.trials] == [t.seq for t in final.completed]
    np.testing.assert_array_equal(trials.trials[0].pose_change, final.completed[0].pose_change)


def _interrupt_on(kind: str, trial: int) -> CallbackObserver:
    def callback(record: Record, state: SessionState) -> None:
        if record.kind == kind and record.data.get("trial") == trial:
            raise KeyboardInterrupt

    return CallbackObserver(callback)


def test_cut_off_at_the_motion_is_void_and_redone(tmp_path: Path) -> None:
    with fake_robot(QUERY) as (robot, truth):
        journal, state = _start(tmp_path, "k=1,l=0.5,n=3")
        source = FakeTruthSource(truth, description(), seed=3)
        with journal, pytest.raises(KeyboardInterrupt):
            SessionEngine(
                journal, state, robot, _tape(source), observer=_interrupt_on(ev.MOTION_START, 2)
            ).run()
        assert not truth.moving()
        kinds = _kinds(tmp_path)
        assert kinds[-3:] == [ev.MOTION_START, ev.VOID, ev.STOPPED]
        stopped = read_journal(tmp_path).records[-1].data
        assert stopped["reason"] == "interrupted"

        resumed = resume_session(tmp_path)
        with resumed.journal:
            final = SessionEngine(resumed.journal, resumed.state, robot, _tape(source)).run()
    assert [(t.trial, t.attempt) for t in final.completed] == [(1, 1), (2, 2), (3, 1)]
    assert final.voided == 1


class _FailingAt(FakeTruthSource):
    """Breaks off (as Ctrl-C would) when asked for one distance of one trial."""

    def __init__(self, *args: Any, trial: int, index: int, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.at = (trial, index)

    def distance(self, ctx: TapeContext, index: int) -> float:
        if (ctx.trial, index) == self.at:
            raise KeyboardInterrupt
        return super().distance(ctx, index)


def test_cut_off_while_measuring_resumes_at_the_next_distance(tmp_path: Path) -> None:
    with fake_robot(QUERY) as (robot, truth):
        journal, state = _start(tmp_path, "k=1,l=0.5,n=2")
        failing = _FailingAt(truth, description(), seed=3, trial=2, index=2)
        with journal, pytest.raises(KeyboardInterrupt):
            SessionEngine(journal, state, robot, _tape(failing)).run()
        before = replay(read_journal(tmp_path).records)
        assert before.open_trial is not None
        assert before.open_trial.phase is Phase.MEASURING
        assert before.open_trial.readings is not None
        assert len(before.open_trial.readings.values) == 2

        source = FakeTruthSource(truth, description(), seed=3)
        resumed = resume_session(tmp_path)
        with resumed.journal:
            final = SessionEngine(resumed.journal, resumed.state, robot, _tape(source)).run()
    assert [(t.trial, t.attempt) for t in final.completed] == [(1, 1), (2, 1)]
    assert final.voided == 0
    second = final.completed[1]
    # the distances taken before and after the break are those of one attempt
    ctx = TapeContext(2, 1, 2, second.design, start=second.start, end=second.end)
    expected = [source.distance(ctx, i) for i in range(5)]
    assert second.readings is not None
    assert list(second.readings.values) == expected
    records = read_journal(tmp_path).records
    indices = [
        r.data["index"] for r in records if r.kind == Measurement.KIND and r.data["trial"] == 2
    ]
    assert indices == [0, 1, 2, 3, 4]


class _OneBadTape(FakeTruthSource):
    """Misreads the first distance by 5 cm on the first try of each attempt."""

    def distance(self, ctx: TapeContext, index: int) -> float:
        value = super().distance(ctx, index)
        return value + 0.05 if (index == 0 and ctx.rejections == 0) else value


def test_inconsistent_distances_are_rejected_and_taken_again(tmp_path: Path) -> None:
    with fake_robot(QUERY) as (robot, truth):
        journal, state = _start(tmp_path, "k=0.5,l=1,n=2")
        with journal:
            final = SessionEngine(
                journal, state, robot, _tape(_OneBadTape(truth, description(), seed=3))
            ).run()
    assert len(final.completed) == 2
    kinds = _kinds(tmp_path)
    assert kinds.count(MeasurementsRejected.KIND) == 2
    assert kinds.count(Measurement.KIND) == 4 * 5


def _trial_file(path: Path, rows: list[tuple[float, float, str, float, float, float]]) -> Path:
    lines = ["k,l_m,variant,dx_m,dy_m,dtheta_rad"]
    lines += [",".join(str(v) for v in row) for row in rows]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def test_recorded_distances_from_a_trial_file(tmp_path: Path) -> None:
    poses = [(0.5, 0.01, -0.02), (0.49, -0.005, 0.01)]
    # the second one-way trial comes back: it is driven backwards
    rows = [(0.5, 0.5, v, *p) for v, p in zip(("turn", "turn-backward"), poses, strict=True)]
    file = _trial_file(tmp_path / "trials.csv", rows)
    source = recorded_source_from_file(file, description())
    with fake_robot(QUERY) as (robot, _):
        journal, state = _start(tmp_path / "s", "k=0.5,l=0.5,n=2")
        with journal:
            final = SessionEngine(journal, state, robot, _tape(source)).run()
    for trial, pose in zip(final.completed, poses, strict=True):
        np.testing.assert_allclose(trial.pose_change, pose, atol=1e-7)


def test_recorded_row_of_another_design_is_refused(tmp_path: Path) -> None:
    file = _trial_file(tmp_path / "trials.csv", [(1.0, 0.5, "turn", 0.0, 0.0, 0.0)])
    source = recorded_source_from_file(file, description())
    with fake_robot(QUERY) as (robot, _):
        journal, state = _start(tmp_path / "s", "k=0.5,l=0.5,n=1")
        with journal, pytest.raises(MeasurementError, match="row 1 is design k=1"):
            SessionEngine(journal, state, robot, _tape(source)).run()
    assert _kinds(tmp_path / "s")[-1] == ev.STOPPED


class _TapeOperator:
    """An operator with a perfect tape behind the wizard's parser: each distance
    is typed with more digits than a float holds ("0.1 + tiny digits"), parsed
    once by :func:`odohil.session.wizard.tape_entry.parse_metres` and handed over as a float;
    ``negative`` makes the interface hand over a negative number instead."""

    def __init__(self, truth: PortTruth, negative: bool = False) -> None:
        self.truth = truth
        self.negative = negative
        self.start = (0.0, 0.0, 0.0)
        self.change = (0.0, 0.0, 0.0)
        self.typed: list[str] = []
        self.given: list[float] = []

    def confirm_start_marks(self, ctx: TapeContext) -> None:
        self.start = self.truth.true_pose()

    def confirm_end_marks(self, ctx: TapeContext) -> None:
        winding = ctx.design.path().winding_rad
        self.change = relative_true_pose(self.start, self.truth.true_pose(), winding)

    def ask_distance(self, ctx: TapeContext, index: int) -> float:
        exact = float(marks_from_pose(description(), self.change).as_array()[index])
        text = f"{exact!r}0000000000071"
        value = -exact if self.negative else parse_metres(text, ctx.labels[index])
        self.typed.append(text)
        self.given.append(value)
        return value

    def show_rejection(self, ctx: TapeContext, reason: str) -> None:
        raise AssertionError(reason)

    def ask_remeasure(self, ctx: TapeContext, index: int, reason: str) -> float | None:
        return None

    def ask_extra_distance(self, ctx: TapeContext, label: str, reason: str) -> float | None:
        return None


def test_a_typed_distance_reaches_the_journal_as_the_same_float(tmp_path: Path) -> None:
    """One parse, one conversion: what the operator typed becomes one float
    (the one Python parses from the text) and the journal holds that float."""
    with fake_robot(QUERY) as (robot, truth):
        journal, state = _start(tmp_path, "k=1,l=1,n=1")
        operator = _TapeOperator(truth)
        with journal:
            SessionEngine(journal, state, robot, _tape(OperatorSource(operator))).run()
    journaled = [
        r.data["value_m"] for r in read_journal(tmp_path).records if r.kind == Measurement.KIND
    ]
    assert journaled == operator.given == [float(text) for text in operator.typed]
    assert all(type(v) is float for v in journaled)
    assert len(journaled) == len(description().screws) + len(description().cross_pairs)


def test_a_distance_that_is_no_distance_is_refused_once_by_name(tmp_path: Path) -> None:
    """The one check (odohil.session.measure.tape.source.check_distance) stands where every
    source's distances enter the session: nothing unchecked reaches the journal."""
    with fake_robot(QUERY) as (robot, truth):
        journal, state = _start(tmp_path, "k=1,l=1,n=1")
        with journal, pytest.raises(MeasurementError, match=r"d1 \(screw A\): a distance cannot"):
            SessionEngine(
                journal, state, robot, _tape(OperatorSource(_TapeOperator(truth, True)))
            ).run()
    kinds = _kinds(tmp_path)
    assert Measurement.KIND not in kinds
    assert kinds[-1] == ev.STOPPED
    with pytest.raises(MeasurementError, match="not a finite number"):
        check_distance(math.nan, "d1")
    assert check_distance(0.25, "d1") == 0.25


class _EstimateWatcher:
    """Sees records and typed live estimates, in order."""

    def __init__(self) -> None:
        self.seen: list[tuple[str, Any]] = []

    def record(self, record: Record, state: SessionState) -> None:
        self.seen.append((record.kind, record.data))

    def estimated(self, result: EstimateResult, state: SessionState) -> None:
        self.seen.append(("estimated", result))


def test_the_live_estimate_crosses_the_session_typed(tmp_path: Path) -> None:
    """The engine and its observers hold an EstimateResult; JSON only in the
    journal's ``estimate`` record, which is exactly its to_json_dict()."""
    watcher = _EstimateWatcher()
    with fake_robot(QUERY) as (robot, truth):
        journal, state = _start(tmp_path, "k=1,l=1,n=3")
        with journal:
            engine = SessionEngine(
                journal,
                state,
                robot,
                _tape(FakeTruthSource(truth, description(), seed=3)),
                estimator=IncrementalLiveEstimator(),
                observer=watcher,
            )
            engine.run()
    assert isinstance(engine.latest_estimate, EstimateResult)
    typed = [(i, v) for i, (kind, v) in enumerate(watcher.seen) if kind == "estimated"]
    assert typed, "no live estimate"
    for i, result in typed:
        kind, data = watcher.seen[i - 1]
        assert kind == ev.ESTIMATE
        assert data["result"] == json.loads(json.dumps(result.to_json_dict()))
    assert typed[-1][1] is engine.latest_estimate


def test_records_go_to_the_observer_in_order(tmp_path: Path) -> None:
    seen: list[tuple[int, str, int]] = []

    def callback(record: Record, state: SessionState) -> None:
        seen.append((record.seq, record.kind, len(state.completed)))

    with fake_robot(QUERY) as (robot, truth):
        journal, state = _start(tmp_path, "k=0.5,l=0.5,n=1")
        with journal:
            SessionEngine(
                journal,
                state,
                robot,
                _tape(FakeTruthSource(truth, description())),
                observer=CallbackObserver(callback),
            ).run()
    kinds = [kind for _, kind, _ in seen]
    assert kinds[:5] == [
        ev.ROBOT, ev.START_POSE, ev.TRIAL_START, ev.MOTION_START, ev.MOTION_DONE,
    ]  # fmt: skip
    assert kinds[-2:] == [ev.SOLVED, ev.FINISHED]
    assert [seq for seq, _, _ in seen] == list(range(2, 2 + len(seen)))
    assert seen[-1][2] == 1


@pytest.mark.parametrize("error", [MemoryError, RuntimeError, SystemExit])
def test_any_exception_during_a_motion_stops_the_robot(
    tmp_path: Path, error: type[BaseException]
) -> None:
    """Not only odohil's own errors: a bug, an out-of-memory error or an exit
    raised while the robot drives stops it, is journaled, and goes on up."""
    raised: list[bool] = []

    def on_sample(sample: OdometrySample) -> None:
        if sample.moving and not raised:
            raised.append(True)
            raise error("raised mid-motion")

    with fake_robot("seed=11&time_scale=1") as (robot, truth):
        journal, state = _start(tmp_path, "k=0.5,l=0.5,n=1")
        source = FakeTruthSource(truth, description(), seed=3)
        with journal, pytest.raises(error):
            SessionEngine(journal, state, robot, _tape(source), on_sample=on_sample).run()
        assert raised
        assert not truth.moving()
    records = read_journal(tmp_path).records
    assert [r.kind for r in records[-3:]] == [ev.MOTION_START, ev.VOID, ev.STOPPED]
    assert records[-1].data["reason"] == "error"
    assert records[-1].data["robot"] == "stopped"
