"""The generic trial context, the engine and the session state name nothing of
the tape (issue 18, deliverable 3).

Before: ``TrialContext`` carried the tape's fields (``labels``,
``measurements``, ``rejections``, ``remeasures``, ``slip``, ``extra``), the
engine built every context with ``labels=()`` and wrapped a tape distance
source itself, and the state named the tape's record kinds
(``MEASUREMENTS_REJECTED``...) and kept a trial's ``slip``. Now a context
carries the source's own readings as one opaque value (``readings``, the
tape's :class:`~odohil.session.measure.tape.records.TapeReadings`), the tape's words
live in the tape's modules, and a flagged trial says why in generic words
(``flag_reason``); the journal on disk is unchanged (tests/session/test_old_journals.py).
"""

from __future__ import annotations

import ast
import dataclasses
import re
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import Any, ClassVar

import odohil.session.journal.state
import odohil.session.measure.protocol
import odohil.session.run.engine
from odohil.session.journal.events import SourceEvent, SourceReadings
from odohil.session.measure.protocol import MeasuredPose, MeasurementLog, TrialContext
from odohil.session.measure.truth import TruthPoseSource
from odohil.session.plans.plan import parse_plan
from odohil.session.run.engine import SessionEngine, start_session
from tests.session.helpers import FAST, ROBOT_TOML, Heard, fake_robot

TAPE_WORDS = frozenset(
    {
        # the tape's context fields and readings
        "labels",
        "measurements",
        "rejections",
        "rejected",
        "remeasure",
        "remeasures",
        "remeasured",
        "slip",
        "extra",
        "distance",
        "distances",
        # the tape itself, its record module and its distance sources
        "tape",
        "measurementsource",
        "operatorsource",
        "faketruthsource",
        "recordedsource",
    }
)
"""Words (lower case, from identifiers split at ``_`` and at capitals) that
belong to the tape: the distances' names and values, their rejections,
re-measures, the slip check's doubt, the extra cross distance, the tape's
distance sources. ``measurement`` alone stays generic, and so does ``label``
(a design's label) (``MeasurementError``,
``MeasuredPose``, ``--measure``)."""

TAPE_RECORD_KINDS = frozenset(
    {"measurement", "measurements_rejected", "remeasured", "extra_distance"}
)
"""The tape's journal record kinds (odohil/session/measure/tape/records.py)."""

GENERIC_MODULES = (
    odohil.session.measure.protocol,
    odohil.session.run.engine,
    odohil.session.journal.state,
)


def _words(identifier: str) -> set[str]:
    """``MEASUREMENTS_REJECTED`` -> {measurements, rejected}; ``TapeSource`` ->
    {tape, source, tapesource}; ``as_pose_source`` -> {as, pose, source}."""
    parts = [p for p in re.split(r"_+", identifier) if p]
    words = {p.lower() for p in parts}
    for part in parts:
        camel = re.findall(r"[A-Z]+(?![a-z])|[A-Z]?[a-z0-9]+", part)
        words |= {w.lower() for w in camel}
    return words


def _names(tree: ast.AST) -> Iterator[tuple[int, str]]:
    """Every identifier the code uses or defines (not docstrings, not comments),
    and every string constant that is one of the tape's record kinds."""
    for node in ast.walk(tree):
        line = getattr(node, "lineno", 0)
        if isinstance(node, ast.Name):
            yield line, node.id
        elif isinstance(node, ast.Attribute):
            yield line, node.attr
        elif isinstance(node, ast.keyword | ast.arg) and node.arg is not None:
            yield line, node.arg
        elif isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
            yield line, node.name
        elif isinstance(node, ast.alias):
            yield line, node.asname or node.name
            yield line, node.name.rsplit(".", 1)[-1]
        elif isinstance(node, ast.ImportFrom) and node.module:
            yield line, node.module.rsplit(".", 1)[-1]
        elif isinstance(node, ast.Constant) and node.value in TAPE_RECORD_KINDS:
            yield line, str(node.value)


def _tape_names(path: Path) -> list[str]:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    return sorted(
        {
            f"{path.name}:{line}: {name}"
            for line, name in _names(tree)
            if _words(name) & TAPE_WORDS or name in TAPE_RECORD_KINDS
        }
    )


def test_the_generic_context_engine_and_state_name_nothing_of_the_tape() -> None:
    found = [hit for module in GENERIC_MODULES for hit in _tape_names(Path(str(module.__file__)))]
    assert found == []


def test_the_trial_context_has_no_tape_field() -> None:
    names = {f.name for f in dataclasses.fields(TrialContext)}
    assert {n for n in names if _words(n) & TAPE_WORDS} == set()
    assert "readings" in names


# --- a source that is not the tape --------------------------------------------


@dataclasses.dataclass(frozen=True)
class Clicked(SourceEvent):
    """A toy source's reading: one click."""

    KIND: ClassVar[str] = "test_tape_context_clicked"
    trial: int
    attempt: int

    def fold(self, readings: SourceReadings | None) -> Heard:
        return Heard((readings.heard if isinstance(readings, Heard) else 0) + 1)


class ClickingTruth:
    """The fake's truth channel with one journaled reading of its own per
    attempt; it keeps every context it is given."""

    def __init__(self, inner: TruthPoseSource) -> None:
        self.inner = inner
        self.seen: list[TrialContext] = []

    def at_start(self, ctx: TrialContext) -> Mapping[str, Any]:
        self.seen.append(ctx)
        return self.inner.at_start(ctx)

    def at_end(self, ctx: TrialContext) -> Mapping[str, Any]:
        self.seen.append(ctx)
        return self.inner.at_end(ctx)

    def pose_change(self, ctx: TrialContext, log: MeasurementLog) -> MeasuredPose:
        self.seen.append(ctx)
        after = log(Clicked(ctx.trial, ctx.attempt))
        self.seen.append(after)
        return self.inner.pose_change(after, log)


def test_a_source_that_is_not_the_tape_gets_its_own_readings_and_no_tape_field(
    tmp_path: Path,
) -> None:
    with fake_robot(f"seed=3&{FAST}") as (robot, truth):
        source = ClickingTruth(TruthPoseSource(truth, (0.002, 0.002, 0.004), seed=1))
        journal, state = start_session(
            tmp_path / "s", ROBOT_TOML, parse_plan("k=1,l=0.5,n=2"), measure="fake", settings={}
        )
        with journal:
            final = SessionEngine(journal, state, robot, source).run()
    assert len(final.completed) == 2
    assert [t.readings for t in final.completed] == [Heard(1), Heard(1)]
    # at_start, at_end, pose_change: no readings yet; after its own log: its own
    assert [ctx.readings for ctx in source.seen] == [None, None, None, Heard(1)] * 2
    for ctx in source.seen:
        fields = {f.name for f in dataclasses.fields(ctx)}
        assert {n for n in fields if _words(n) & TAPE_WORDS} == set()
        assert type(ctx) is TrialContext
