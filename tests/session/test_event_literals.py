"""No journal event is written as a dict literal outside the journal's edge
(odohil/session/journal/file.py and odohil/session/journal/events.py): the engine, the
sources and the CLI hand typed events (odohil/session/journal/events.py,
odohil/session/measure/tape/records.py) to ``Journal.write``."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from odohil.session.journal import events
from odohil.session.journal.events import event_types

ROOT = Path(__file__).resolve().parents[2]
PACKAGE = ROOT / "odohil"
EDGE = {Path("odohil/session/journal/file.py"), Path("odohil/session/journal/events.py")}
"""The journal's edge: the only files where an event is JSON."""

KINDS = frozenset(event_types())
KIND_NAMES = frozenset(
    name
    for name in dir(events)
    if name.isupper() and isinstance(getattr(events, name), str) and getattr(events, name) in KINDS
) | frozenset(kind.upper() for kind in KINDS)
"""The constants that name a kind (``events.SOLVED``...; a pose source's kinds,
which the events module does not name, by their upper-case spelling: ``MEASUREMENTS_REJECTED``)."""


def _names_a_kind(node: ast.expr) -> bool:
    """``node`` is an event kind: "solved", ``ev.SOLVED``, ``SOLVED``, ``Solved.KIND``."""
    if isinstance(node, ast.Constant):
        return node.value in KINDS
    if isinstance(node, ast.Attribute):
        return node.attr in KIND_NAMES or node.attr == "KIND"
    if isinstance(node, ast.Name):
        return node.id in KIND_NAMES
    return False


def _is_dict(node: ast.expr) -> bool:
    """A dict literal or ``dict(...)``."""
    return isinstance(node, ast.Dict) or (
        isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == "dict"
    )


def _raw_append(node: ast.Call) -> bool:
    """``<...journal>.append(...)``: the journal's raw, untyped append."""
    func = node.func
    if not (isinstance(func, ast.Attribute) and func.attr == "append"):
        return False
    return ast.unparse(func.value).lower().endswith("journal")


def event_literals(source: str, where: str = "<source>") -> list[str]:
    """Where ``source`` writes a journal event as a dict (``where:line: what``)."""
    found: list[str] = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Dict):
            for key, value in zip(node.keys, node.values, strict=True):
                if (
                    isinstance(key, ast.Constant)
                    and key.value == "kind"
                    and value is not None
                    and _names_a_kind(value)
                ):
                    found.append(f"{where}:{node.lineno}: a dict with an event kind")
        if isinstance(node, ast.Call):
            args = [*node.args, *(k.value for k in node.keywords)]
            if _raw_append(node):
                found.append(f"{where}:{node.lineno}: the journal's raw append")
            elif any(_is_dict(a) for a in args) and any(_names_a_kind(a) for a in args):
                found.append(f"{where}:{node.lineno}: an event kind with a dict")
    return found


# what odohil wrote before the events were typed (engine.py, sources.py, since moved)
TODAYS = [
    'self._log(ev.FINISHED, {"n_trials": len(self.state.completed)})',
    'ctx = log(ev.MEASUREMENTS_REJECTED, {**ids, "reason": str(exc)})',
    "state = apply(state, journal.append(ev.RESUMED, dict(note or {})))",
    "record = self.journal.append(kind, data)",
    'self.journal.append("void", {"trial": 1, "attempt": 1, "reason": "x"})',
    'line = {"kind": "solved", "data": {}}',
]


@pytest.mark.parametrize("snippet", TODAYS)
def test_the_check_finds_the_dict_events_odohil_wrote_before(snippet: str) -> None:
    assert event_literals(snippet)


@pytest.mark.parametrize(
    "snippet",
    [
        'self._log(Void(opened.trial, opened.attempt, reason="x"))',
        'rows.append({"turn_rad": step.angle_rad, "kind": step.kind})',
        'lines.append(",".join(values))',
        'table = {"kind": self.kind, "group": 1}',
    ],
)
def test_the_check_leaves_typed_events_and_other_dicts_alone(snippet: str) -> None:
    assert event_literals(snippet) == []


def test_no_event_dict_literal_outside_the_journal_module() -> None:
    found: list[str] = []
    for path in sorted(PACKAGE.rglob("*.py")):
        relative = path.relative_to(ROOT)
        if relative in EDGE:
            continue
        found += event_literals(path.read_text(encoding="utf-8"), str(relative))
    assert found == []


TAPE_NAMES = frozenset(
    {"rejections", "remeasures", "extra", "labels", "distance_labels", "MarkDistances"}
)
"""The tape's own fields and helpers (odohil/session/measure/tape/records.py)."""


def tape_names(source: str) -> set[str]:
    """The tape's names ``source`` reads or sets (attributes, names, keywords)."""
    found: set[str] = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Attribute) and node.attr in TAPE_NAMES:
            found.add(node.attr)
        elif isinstance(node, ast.Name) and node.id in TAPE_NAMES:
            found.add(node.id)
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            if node.target.id in TAPE_NAMES:
                found.add(node.target.id)
        elif isinstance(node, ast.keyword) and node.arg in TAPE_NAMES and node.arg != "labels":
            found.add(node.arg)
    return found


def test_the_check_finds_the_tape_fields_the_engine_and_state_carried_before() -> None:
    before = "self.labels = distance_labels(d)\nrejections: int = 0\nx = opened.remeasures"
    assert tape_names(before) == {"labels", "distance_labels", "rejections", "remeasures"}


@pytest.mark.parametrize(
    "module", ["odohil/session/run/engine.py", "odohil/session/journal/state.py"]
)
def test_the_engine_and_the_state_carry_nothing_of_the_tape(module: str) -> None:
    """The tape's readings are its own record (TapeReadings), opaque here."""
    assert tape_names((ROOT / module).read_text(encoding="utf-8")) == set()
