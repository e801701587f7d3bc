"""Replaying journal records into the session state."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import pytest

from odohil.errors import JournalError
from odohil.session.journal import events as ev
from odohil.session.journal.events import Estimate
from odohil.session.journal.file import Record
from odohil.session.journal.state import Phase, replay
from odohil.session.measure.tape.records import Measurement, MeasurementsRejected
from odohil.session.plans.plan import parse_plan
from tests.session.helpers import readings_of

PLAN = parse_plan("k=1,l=1,n=2;k=0.5,l=2,n=1")


class Log:
    """Builds a record list the way the engine journals it."""

    def __init__(self) -> None:
        self.records: list[Record] = []
        self.add(ev.SESSION, {"format": ev.FORMAT})
        self.add(ev.PLAN, PLAN.to_json())

    def add(self, kind: str, data: Mapping[str, Any]) -> None:
        self.records.append(Record(len(self.records) + 1, kind, 0.0, data))

    def start(self, trial: int, attempt: int = 1) -> None:
        design = PLAN.design_index(trial)
        self.add(
            ev.TRIAL_START, {"trial": trial, "attempt": attempt, "design": design, "start": {}}
        )

    def move(self, trial: int, attempt: int = 1) -> None:
        ids = {"trial": trial, "attempt": attempt}
        self.add(ev.MOTION_START, ids)
        self.add(ev.MOTION_DONE, {**ids, "encoder_end_pose": [0.0, 0.0, 0.0], "end": {"x": 1}})

    def measure(self, trial: int, values: list[float], attempt: int = 1) -> None:
        for index, value in enumerate(values):
            self.add(
                Measurement.KIND,
                {
                    "trial": trial,
                    "attempt": attempt,
                    "index": index,
                    "label": "d",
                    "value_m": value,
                },
            )

    def solve(self, trial: int, attempt: int = 1) -> None:
        self.add(
            ev.SOLVED,
            {
                "trial": trial,
                "attempt": attempt,
                "pose_change": [0.01, 0.02, 0.003],
                "cov": [[1e-6, 0, 0], [0, 1e-6, 0], [0, 0, 1e-5]],
                "chi2": 0.5,
                "clear_cut": True,
                "reason": "",
            },
        )

    def full(self, trial: int, attempt: int = 1) -> None:
        self.start(trial, attempt)
        self.move(trial, attempt)
        self.measure(trial, [0.1, 0.2, 0.3, 0.4], attempt)
        self.solve(trial, attempt)


def test_completed_trials_in_order() -> None:
    log = Log()
    log.full(1)
    log.full(2)
    state = replay(log.records)
    assert state.plan == PLAN
    assert [t.trial for t in state.completed] == [1, 2]
    assert readings_of(state.completed[0]) == (0.1, 0.2, 0.3, 0.4)
    assert state.completed[0].pose_change == (0.01, 0.02, 0.003)
    assert state.completed[1].design == PLAN.items[0].design
    assert state.open_trial is None
    assert state.next_trial() == 3
    assert not state.finished


def test_phases_of_an_open_trial() -> None:
    log = Log()
    log.start(1)
    assert replay(log.records).open_trial.phase is Phase.MARKED  # type: ignore[union-attr]
    log.add(ev.MOTION_START, {"trial": 1, "attempt": 1})
    assert replay(log.records).open_trial.phase is Phase.MOVING  # type: ignore[union-attr]
    log.add(ev.MOTION_DONE, {"trial": 1, "attempt": 1, "encoder_end_pose": [1, 2, 3]})
    log.measure(1, [0.5, 0.6])
    opened = replay(log.records).open_trial
    assert opened is not None
    assert opened.phase is Phase.MEASURING
    assert opened.encoder_end_pose == (1.0, 2.0, 3.0)
    assert readings_of(opened) == (0.5, 0.6)


def test_void_then_a_new_attempt() -> None:
    log = Log()
    log.start(1)
    log.add(ev.MOTION_START, {"trial": 1, "attempt": 1})
    log.add(ev.VOID, {"trial": 1, "attempt": 1, "reason": "cut off during motion"})
    state = replay(log.records)
    assert state.open_trial is None
    assert state.voided == 1
    assert state.next_trial() == 1
    assert state.next_attempt(1) == 2
    log.full(1, attempt=2)
    state = replay(log.records)
    assert [(t.trial, t.attempt) for t in state.completed] == [(1, 2)]


def test_rejected_measurements_are_taken_again() -> None:
    log = Log()
    log.start(1)
    log.move(1)
    log.measure(1, [9.0, 9.0, 9.0, 9.0])
    log.add(MeasurementsRejected.KIND, {"trial": 1, "attempt": 1, "reason": "inconsistent"})
    log.measure(1, [0.1, 0.2, 0.3, 0.4])
    log.solve(1)
    assert readings_of(replay(log.records).completed[0]) == (0.1, 0.2, 0.3, 0.4)


def test_finished_and_estimate() -> None:
    log = Log()
    for trial in (1, 2, 3):
        log.full(trial)
        log.add(ev.ESTIMATE, {"n_trials": trial, "result": {}})
    log.add(ev.FINISHED, {"n_trials": 3})
    state = replay(log.records)
    assert state.finished
    assert state.next_trial() is None
    assert state.last_estimate == Estimate(n_trials=3, result={})


def test_a_trial_solved_twice_is_an_error() -> None:
    log = Log()
    log.full(1)
    log.solve(1)
    with pytest.raises(JournalError, match="not the open trial"):
        replay(log.records)


def test_a_completed_trial_cannot_start_again() -> None:
    log = Log()
    log.full(1)
    log.full(1, attempt=2)
    with pytest.raises(JournalError, match="started again after it completed"):
        replay(log.records)


def test_overlapping_trials_are_an_error() -> None:
    log = Log()
    log.start(1)
    log.start(2)
    with pytest.raises(JournalError, match="still open"):
        replay(log.records)


def test_measurement_before_motion_is_an_error() -> None:
    log = Log()
    log.start(1)
    log.measure(1, [0.1])
    with pytest.raises(JournalError, match="while trial 1 is marked"):
        replay(log.records)


def test_wrong_design_for_the_trial_is_an_error() -> None:
    log = Log()
    log.add(ev.TRIAL_START, {"trial": 3, "attempt": 1, "design": 0, "start": {}})
    with pytest.raises(JournalError, match="plan says 1"):
        replay(log.records)


def test_journal_must_start_with_a_session() -> None:
    with pytest.raises(JournalError, match="must start with a session"):
        replay([Record(1, ev.PLAN, 0.0, PLAN.to_json())])
    with pytest.raises(JournalError, match="format"):
        replay([Record(1, ev.SESSION, 0.0, {"format": 99})])


def test_malformed_record_names_its_sequence_number() -> None:
    log = Log()
    log.start(1)
    log.add(ev.MOTION_START, {"trial": 1, "attempt": 1})
    log.add(ev.MOTION_DONE, {"trial": 1, "attempt": 1, "encoder_end_pose": [1, 2]})
    with pytest.raises(JournalError, match=r"record 5 \(motion_done\) is malformed"):
        replay(log.records)


def test_the_plan_may_come_with_the_session_record() -> None:
    state = replay([Record(1, ev.SESSION, 0.0, {"format": ev.FORMAT, "plan": PLAN.to_json()})])
    assert state.plan == PLAN
    assert state.next_trial() == 1
    with pytest.raises(JournalError, match="bad plan"):
        replay([Record(1, ev.SESSION, 0.0, {"format": ev.FORMAT, "plan": {"designs": 3}})])
