"""Issue 18's acceptance point "odohil/cli/ at most 2,400 lines": the command
line parses, calls the session layer and renders; what it decides lives in
the session layer (docs/architecture.md, "The command line"). Counted as
``wc -l odohil/cli/*.py`` counts."""

from __future__ import annotations

from pathlib import Path

CLI = Path(__file__).resolve().parents[2] / "odohil" / "cli"
MAX_LINES = 2400


def test_the_cli_is_at_most_2400_lines() -> None:
    lines = {path.name: path.read_bytes().count(b"\n") for path in sorted(CLI.glob("*.py"))}
    assert "wizard.py" in lines
    assert sum(lines.values()) <= MAX_LINES, sorted(lines.items(), key=lambda item: -item[1])
