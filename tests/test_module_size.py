"""Issue 32's "no module over 800 lines": a module that grows past it is split by
concept (docs/architecture.md), as science/path_plans.py was. Counted as
``wc -l`` counts, over every module of odohil/ and fakes/."""

from __future__ import annotations

from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
MAX_LINES = 800


def _lines() -> dict[str, int]:
    return {
        str(path.relative_to(ROOT)): path.read_bytes().count(b"\n")
        for package in ("odohil", "fakes")
        for path in sorted((ROOT / package).rglob("*.py"))
    }


def test_no_module_is_over_800_lines() -> None:
    lines = _lines()
    assert "odohil/session/run/engine.py" in lines
    assert "fakes/create2/config.py" in lines
    too_long = {name: count for name, count in lines.items() if count > MAX_LINES}
    assert not too_long, sorted(too_long.items(), key=lambda item: -item[1])
