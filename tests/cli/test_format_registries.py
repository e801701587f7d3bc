"""A new log or export format is its module and one registry entry (issue 32,
python-can's backends, pyserial's URL handlers): the command line offers the
registries' names, and holds no list of its own to edit."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest
from typer.testing import CliRunner

from odohil.cli import export, recording_options
from odohil.cli.app import app
from odohil.session.results.exports import EXPORT_FORMATS
from odohil.session.trials.logs import READERS

CLI = Path(__file__).resolve().parents[2] / "odohil" / "cli"


def test_the_choices_are_the_registries() -> None:
    assert [c.value for c in export.FormatChoice] == list(EXPORT_FORMATS)
    assert [c.value for c in recording_options.FormatChoice] == list(READERS)


@pytest.mark.parametrize("name", list(EXPORT_FORMATS))
def test_export_takes_every_registered_format(name: str) -> None:
    # any format name gets past the option's parsing to the missing source (exit 2)
    result = CliRunner().invoke(app, ["export", "no-such-session", "--format", name])
    assert result.exit_code == 2, result.output
    assert "Invalid value for '--format'" not in result.output


def test_no_cli_module_spells_a_format_name() -> None:
    names = set(EXPORT_FORMATS) | set(READERS)
    found = [
        f"{path.name}:{node.lineno}: {node.value!r}"
        for path in sorted(CLI.glob("*.py"))
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8")))
        if isinstance(node, ast.Constant) and node.value in names
    ]
    assert found == []
