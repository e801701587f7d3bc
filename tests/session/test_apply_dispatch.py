"""The typed events and their dispatch (odohil/session/journal/events.py,
odohil/session/journal/state.py): every kind has one handler, JSON only at the
journal's edge, a pose source's own readings pass the state unopened."""

from __future__ import annotations

from dataclasses import dataclass, fields, replace
from typing import ClassVar

import pytest

from odohil.errors import JournalError
from odohil.session.journal import state as st
from odohil.session.journal.events import (
    FORMAT,
    Estimate,
    Event,
    Finished,
    MotionDone,
    MotionStart,
    PlanSet,
    Resumed,
    RobotConnected,
    SessionHeader,
    Solved,
    SourceEvent,
    SourceReadings,
    StartPoseChecked,
    Stopped,
    StopUnconfirmed,
    TornRecordKept,
    TrialStart,
    Void,
    decode,
    encode,
    event_types,
)
from odohil.session.journal.file import Journal, Record, read_journal
from odohil.session.journal.state import Phase, SessionState, apply, apply_event, replay
from odohil.session.measure.protocol import TrialContext
from odohil.session.measure.tape.records import (
    ExtraDistance,
    Measurement,
    MeasurementsRejected,
    Remeasured,
    TapeContext,
    TapeReadings,
)
from odohil.session.plans.plan import parse_plan
from tests.session.helpers import Heard

PLAN = parse_plan("k=1,l=1,n=2")
COV = ((1e-6, 0.0, 0.0), (0.0, 1e-6, 0.0), (0.0, 0.0, 1e-5))
ONE_OF_EACH: list[Event] = [
    SessionHeader(format=1, odohil="0.1", robot_toml="", measure="fake", plan=PLAN),
    PlanSet(PLAN),
    RobotConnected(connection={"port": "x"}, motion={}, state={"x_m": 0.0}),
    Resumed({"by": "test"}),
    TornRecordKept(file="journal.torn-3.bin", line=3, bytes=10, reason="cut"),
    StartPoseChecked(actual=(0.0, 0.0, 0.0), ok=True, trial=1, expected=(0.0, 0.0, 0.0)),
    TrialStart(1, 1, design=0, backward=False, zeroed={}, start={"true_pose": [0, 0, 0]}),
    MotionStart(1, 1),
    MotionDone(1, 1, encoder_end_pose=(1.0, 0.0, 0.1), duration_s=2.0, trajectory=((0.0, 1.0),)),
    Measurement(1, 1, index=0, value_m=0.25, label="A"),
    MeasurementsRejected(1, 1, reason="no rigid motion"),
    Remeasured(1, 1, index=0, reason="slip", kept=False, previous_m=0.2, value_m=0.21, label="A"),
    ExtraDistance(1, 1, start="A", end="C", value_m=0.3, label="A start to C end"),
    Solved(1, 1, (0.01, 0.0, 0.1), COV, clear_cut=True, flag_reason="kept", details={"chi2": 0.5}),
    Estimate(2, result={"n_trials": 2}),
    Void(1, 2, reason="interrupted"),
    Stopped("interrupted", "Ctrl-C", state={"x_m": 0.0}),
    StopUnconfirmed("error", "boom", detail="no reply"),
    Finished(n_trials=2),
]


def test_every_kind_round_trips_through_its_json() -> None:
    odohils = {c for c in event_types().values() if c.__module__.startswith("odohil.")}
    assert {type(e) for e in ONE_OF_EACH} == odohils
    for event in ONE_OF_EACH:
        kind, data = encode(event)
        assert kind == event.KIND
        assert decode(kind, data) == event


def test_every_kind_has_one_handler() -> None:
    for kind, cls in event_types().items():
        assert cls in st._HANDLERS or issubclass(cls, SourceEvent), kind


def test_a_solved_records_source_details_are_its_own_members() -> None:
    """The ``solved`` record keeps the source's details as members, as always."""
    kind, data = encode(ONE_OF_EACH[13])
    assert data["chi2"] == 0.5
    assert "details" not in data
    assert decode(kind, {**data, "check": {"T": 1.0}}).details == {"chi2": 0.5, "check": {"T": 1.0}}


def _state() -> SessionState:
    header = SessionHeader(format=FORMAT, plan=PLAN)
    return SessionState(header=header, plan=PLAN, n_records=1)


def _run(state: SessionState, *events: Event) -> SessionState:
    for event in events:
        state = apply_event(state, event, state.n_records + 1)
    return state


def test_the_tape_readings_fold_into_the_open_attempts_own_record() -> None:
    state = _run(
        _state(),
        TrialStart(1, 1, design=0),
        MotionStart(1, 1),
        MotionDone(1, 1, encoder_end_pose=(0.0, 0.0, 0.0)),
        Measurement(1, 1, 0, 0.1),
        Measurement(1, 1, 1, 0.2),
        MeasurementsRejected(1, 1, "x"),
        Measurement(1, 1, 0, 0.11),
        Measurement(1, 1, 1, 0.21),
        Remeasured(1, 1, index=1, reason="slip", kept=False, value_m=0.22),
        ExtraDistance(1, 1, "A", "C", 0.3),
    )
    assert state.open_trial is not None
    assert state.open_trial.readings == TapeReadings(
        measurements=(0.11, 0.22), rejections=1, remeasures=1, extra=(("A", "C", 0.3),)
    )
    ctx = TrialContext(1, 1, 2, PLAN.design_of(1), readings=state.open_trial.readings)
    assert TapeContext.of(ctx, ("d1", "d2")).rejections == 1
    done = _run(state, Solved(1, 1, (0.0, 0.0, 0.0), COV, clear_cut=True))
    assert done.completed[0].readings is not None
    assert done.completed[0].readings.values == (0.11, 0.22)
    assert done.completed[0].readings == state.open_trial.readings


@dataclass(frozen=True)
class Beeped(SourceEvent):
    """A toy source's reading: one beep."""

    KIND: ClassVar[str] = "test_beeped"
    trial: int
    attempt: int

    def fold(self, readings: SourceReadings | None) -> Heard:
        heard = readings.heard if isinstance(readings, Heard) else 0
        return Heard(heard + 1)


def test_another_sources_readings_pass_the_state_unopened(tmp_path: object) -> None:
    """A source the state has never heard of journals its own readings; the
    state folds them by the event's own rule and keeps them with the trial."""
    state = _run(
        _state(),
        TrialStart(1, 1, design=0),
        MotionStart(1, 1),
        MotionDone(1, 1, encoder_end_pose=(0.0, 0.0, 0.0)),
        Beeped(1, 1),
        Beeped(1, 1),
        Solved(1, 1, (0.0, 0.0, 0.0), COV, clear_cut=True),
    )
    assert state.completed[0].readings == Heard(2)
    assert state.completed[0].readings.values == (2.0,)


def test_the_journal_writes_typed_events_and_replay_reads_them_back(tmp_path: object) -> None:
    from pathlib import Path

    folder = Path(str(tmp_path))
    live = _state()
    events: list[Event] = [
        TrialStart(1, 1, design=0, start={"true_pose": [0.0, 0.0, 0.0]}),
        MotionStart(1, 1),
        MotionDone(1, 1, encoder_end_pose=(0.5, 0.0, 0.0), trajectory=((0.0, 0.0, 0.0, 0.0),)),
        Measurement(1, 1, 0, 0.1, "A"),
        Solved(1, 1, (0.5, 0.0, 0.0), COV, clear_cut=True, details={"chi2": 0.1}),
        Estimate(1, result=None, error="too few trials"),
    ]
    with Journal.create(folder) as journal:
        header = journal.write(live.header)
        for event in events:
            record = journal.write(event)
            assert record.event == event
            live = apply(live, record)
    replayed = replay(read_journal(folder).records)
    assert header.kind == "session"
    assert replayed.completed == live.completed
    assert replayed.last_estimate == Estimate(1, result=None, error="too few trials")


@pytest.mark.parametrize(
    ("event", "message"),
    [
        (
            Measurement(1, 1, 1, 0.1),
            r"record 5 \(measurement\) is malformed: measurement 1 where 0",
        ),
        (Remeasured(1, 1, 0, "slip", kept=True), "re-measured distance 0 was not taken"),
        (Solved(1, 2, (0.0, 0.0, 0.0), COV, clear_cut=True), "not the open trial"),
        (MotionStart(1, 1), "motion_start while trial 1 is measuring, not marked"),
        (SessionHeader(format=1), "a second session record"),
        (PlanSet(PLAN), "a second plan"),
    ],
)
def test_an_event_that_does_not_fit_is_refused_by_record(event: Event, message: str) -> None:
    state = _run(
        _state(),
        TrialStart(1, 1, design=0),
        MotionStart(1, 1),
        MotionDone(1, 1, encoder_end_pose=(0.0, 0.0, 0.0)),
    )
    with pytest.raises(JournalError, match=message):
        apply_event(state, event, 5)


def test_a_member_of_the_wrong_type_is_named() -> None:
    state = _run(_state(), TrialStart(1, 1, design=0), MotionStart(1, 1))
    bad = Record(4, "motion_done", 0.0, {"trial": 1, "attempt": 1, "encoder_end_pose": [0, "x", 0]})
    with pytest.raises(JournalError, match=r"record 4 \(motion_done\) is malformed: encoder_end"):
        apply(state, bad)
    with pytest.raises(JournalError, match="record 4: unknown event kind 'teleported'"):
        apply(state, Record(4, "teleported", 0.0, {}))


def test_information_records_leave_the_state_alone() -> None:
    state = _state()
    for event in ONE_OF_EACH[2:6] + ONE_OF_EACH[16:18]:
        after = apply_event(state, event, 2)
        assert replace(after, n_records=state.n_records) == state
    assert [f.name for f in fields(Solved)][:2] == ["trial", "attempt"]
    assert _run(state, Finished(0)).finished
    assert _run(state, Estimate(0)).last_estimate == Estimate(0)
    assert Phase.MEASURING.value == "measuring"
