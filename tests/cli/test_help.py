"""The help texts say what the commands do, legibly (issue 18): the robot
description's TOML section names survive rich markup, flags carry no stray
metavar, the top-level help and emulate's name both robots, and ``--version``
has its short form. In process through typer's runner."""

from __future__ import annotations

import re

import pytest
import typer
from typer.testing import CliRunner

from odohil import __version__
from odohil.cli.app import COMMAND_MODULES, app

SECTION = re.compile(r"\[(serial|robot|floor|measurement|screws)\]")


def help_of(*command: str) -> str:
    result = CliRunner().invoke(app, [*command, "--help"], env={"COLUMNS": "200"})
    assert result.exit_code == 0, result.output
    return " ".join(result.output.split())


def sources_of(command: str) -> list[str]:
    """The help strings a command's help is rendered from."""
    click_command = typer.main.get_command(app).commands[command]  # type: ignore[attr-defined]
    texts = [click_command.help or ""]
    texts += [getattr(p, "help", None) or "" for p in click_command.params]
    return texts


@pytest.mark.parametrize("command", COMMAND_MODULES)
def test_toml_section_names_are_printed(command: str) -> None:
    shown = help_of(command)
    wanted = {m.group(0) for text in sources_of(command) for m in SECTION.finditer(text)}
    missing = [name for name in sorted(wanted) if name not in shown]
    assert missing == [], (command, missing)


def test_section_names_reach_run_and_wizard_help() -> None:
    assert "robot.toml [serial] port" in help_of("run")
    assert "([robot] turns_exact = false)" in help_of("run")
    assert "robot.toml [serial] baud" in help_of("wizard")


@pytest.mark.parametrize("command", ["", *COMMAND_MODULES])
def test_flags_show_no_metavar(command: str) -> None:
    shown = help_of(*([command] if command else []))
    assert "<bool>" not in shown


def test_the_top_level_help_names_both_drives() -> None:
    shown = help_of()
    assert "synchronous" in shown
    assert "differential" in shown


def test_emulate_help_names_both_fakes_and_their_own_line_rates() -> None:
    shown = help_of("emulate")
    assert "fake robot" in shown
    assert "Create 2" in shown
    assert "[default: 38400]" not in shown  # the Create 2 speaks 115200


@pytest.mark.parametrize("flag", ["--version", "-V"])
def test_version(flag: str) -> None:
    result = CliRunner().invoke(app, [flag])
    assert result.exit_code == 0, result.output
    assert result.output == f"odohil {__version__}\n"
