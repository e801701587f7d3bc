"""Journals written by an earlier odohil (tests/session/data/make_journals.py,
before the journal events were typed) still replay to the same session state
and the same estimate: a finished session, an interrupted and resumed one left
open mid-measurement, a wizard session with a rejection, a re-measure and a
kept suspect distance, one with extra distances for ambiguous trials, and one
measured as poses (no tape)."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import pytest

from odohil.session.journal.events import encode
from odohil.session.journal.state import load_session, session_trials
from odohil.session.measure.tape.records import TapeReadings
from odohil.session.run.engine import IncrementalLiveEstimator

JOURNALS = Path(__file__).resolve().parent / "data" / "journals"


def _open_trial(state: Any) -> dict[str, Any] | None:
    opened = state.open_trial
    if opened is None:
        return None
    tape = opened.readings or TapeReadings()
    assert isinstance(tape, TapeReadings)
    return {
        "trial": opened.trial,
        "attempt": opened.attempt,
        "design_index": opened.design_index,
        "phase": opened.phase.value,
        "start": dict(opened.start),
        "end": dict(opened.end),
        "encoder_end_pose": opened.encoder_end_pose,
        "n_trajectory": len(opened.trajectory),
        "measurements": list(tape.measurements),
        "rejections": tape.rejections,
        "remeasures": tape.remeasures,
        "slip": tape.slip,
        "extra": [list(e) for e in tape.extra],
    }


def snapshot(folder: Path) -> dict[str, Any]:
    """What a session folder replays to, as JSON (the test compares)."""
    state = load_session(folder).state
    estimator = IncrementalLiveEstimator()
    result = None
    for trial in state.completed:
        if not trial.ambiguous:
            result = estimator.add(trial)
    trials = session_trials(state)
    last = state.last_estimate
    snap = {
        "header": encode(state.header)[1],
        "plan": state.plan.to_json() if state.plan is not None else None,
        "completed": [
            {
                "trial": t.trial,
                "attempt": t.attempt,
                "design": t.design.label(),
                "design_index": t.design_index,
                "encoder_end_pose": t.encoder_end_pose,
                "measurements": list(t.readings.values) if t.readings is not None else [],
                "pose_change": t.pose_change,
                "cov": t.cov,
                "clear_cut": t.clear_cut,
                "start": dict(t.start),
                "end": dict(t.end),
                "note": t.note,
                "seq": t.seq,
                "ambiguous": t.ambiguous,
                "candidates": t.candidates,
                "slip": t.flag_reason,
            }
            for t in state.completed
        ],
        "open_trial": _open_trial(state),
        "voided": state.voided,
        "attempts": {str(k): v for k, v in sorted(state.attempts.items())},
        "last_estimate": {"n_trials": last.n_trials, "result": last.result} if last else None,
        "finished": state.finished,
        "n_records": state.n_records,
        "trial_set": [
            {"number": t.number, "line": t.line, "flagged": t.flagged, "note": t.note}
            for t in trials.trials
        ],
        "n_ambiguous": len(trials.ambiguous),
        "estimate": result.to_json_dict() if result is not None else None,
    }
    return json.loads(json.dumps(snap))


EXPECTED: dict[str, Any] = (
    json.loads((JOURNALS / "expected.json").read_text(encoding="utf-8"))
    if (JOURNALS / "expected.json").exists()
    else {}
)


def _differences(got: Any, want: Any, where: str = "estimate") -> list[str]:
    """Where two JSON values differ: numbers beyond a relative 1e-3, anything
    else at all. The estimate is recomputed: its optimiser stops within a
    tolerance, so a change of the moments' rounding (1e-10 relative, batched
    instead of design by design) moved E_T by 4e-7 (2e-4 of itself, a fraction
    of a percent of its standard error); a replay that differs moves it by far
    more."""
    if isinstance(want, bool) or not isinstance(want, int | float):
        if isinstance(want, dict) and isinstance(got, dict) and got.keys() == want.keys():
            return [d for k in want for d in _differences(got[k], want[k], f"{where}.{k}")]
        if isinstance(want, list) and isinstance(got, list) and len(got) == len(want):
            return [
                d for i, (g, w) in enumerate(zip(got, want, strict=True))
                for d in _differences(g, w, f"{where}[{i}]")
            ]  # fmt: skip
        return [] if got == want else [f"{where}: {got!r} != {want!r}"]
    close = isinstance(got, int | float) and not isinstance(got, bool)
    close = close and math.isclose(got, want, rel_tol=1e-3, abs_tol=1e-15)
    return [] if close else [f"{where}: {got!r} != {want!r}"]


@pytest.mark.parametrize("name", ["finished", "interrupted", "wizard", "extra", "truth_poses"])
def test_an_old_journal_replays_to_the_same_state_and_estimate(name: str) -> None:
    """The state exactly; the estimate to a relative 1e-3 (:func:`_differences`)."""
    got, want = snapshot(JOURNALS / name), EXPECTED[name]
    assert {k: v for k, v in got.items() if k != "estimate"} == {
        k: v for k, v in want.items() if k != "estimate"
    }
    assert _differences(got["estimate"], want["estimate"]) == []


def test_the_old_journals_hold_every_kind_of_event() -> None:
    """The journals above exercise every event kind today's engine writes."""
    kinds: set[str] = set()
    for name in EXPECTED:
        for line in (JOURNALS / name / "journal.jsonl").read_text(encoding="utf-8").splitlines():
            kinds.add(json.loads(line)["kind"])
    assert kinds >= {
        "session", "robot", "resumed", "trial_start", "motion_start", "motion_done",
        "measurement", "measurements_rejected", "remeasured", "extra_distance", "solved",
        "estimate", "void", "stopped", "finished", "start_pose",
    }  # fmt: skip
