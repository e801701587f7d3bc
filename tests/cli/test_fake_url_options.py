"""A bad option in a fake robot's URL (``fakerobot://``, ``fakecreate2://``) is
bad input: exit 2, with a message naming the option and what is accepted, and
nothing moved. The fake's URL handler raises a ValueError subclass that
pyserial passes through (odohil/errors.py ``PortOptionError``), which the
driver's port opening (odohil/driver/port.py) keeps, so the session and the
driver name no fake. In process (typer's CliRunner)."""

from __future__ import annotations

from pathlib import Path

import pytest
from typer.testing import CliRunner

from odohil.cli.app import app
from odohil.cli.exit_codes import EXIT_BAD_INPUT

CASES = [
    ("nomad150", "fakerobot://?bogus=1", "unknown option 'bogus'", "seed, time_scale"),
    ("nomad150", "fakerobot://?seed=abc", "seed must be an integer, got 'abc'", ""),
    ("nomad150", "fakerobot://?time_scale=x", "time_scale must be a number, got 'x'", ""),
    ("nomad150", "fakerobot://?fault=nosuch", "fault", "known: corrupt"),
    ("create2", "fakecreate2://?bogus=1", "unknown option 'bogus'", "seed, time_scale"),
    ("create2", "fakecreate2://?seed=abc", "seed must be an integer, got 'abc'", ""),
]


@pytest.mark.parametrize(("robot", "port", "names", "accepted"), CASES)
def test_a_bad_fake_url_option_exits_2(
    tmp_path: Path, robot: str, port: str, names: str, accepted: str
) -> None:
    args = [
        "run", "--port", port, "--robot", robot, "--plan", "k=0.5,l=1,n=2",
        "--allow-few-trials", "--session", str(tmp_path / "s"), "--measure", "fake",
    ]  # fmt: skip
    result = CliRunner().invoke(app, args)
    text = " ".join(result.output.split())
    assert result.exit_code == EXIT_BAD_INPUT, text
    assert names in text
    assert accepted in text
    assert "nothing moved" in text
    assert not (tmp_path / "s").exists()
