"""A ``--json`` command that refuses its input prints one JSON object on
stdout besides its exit status and the message on stderr (issue 30, part 4b):
before, ``estimate``/``run``/``validate --json`` printed nothing on stdout."""

from __future__ import annotations

import json
from pathlib import Path

from typer.testing import CliRunner

from odohil.cli.app import app
from odohil.cli.exit_codes import EXIT_BAD_INPUT, EXIT_ERROR
from odohil.robots import __file__ as robots_init

NOMAD = Path(robots_init).with_name("nomad150.toml")
NO_PORT = "/dev/odohil-no-such-port"


def _refused(args: list[str], status: int = EXIT_BAD_INPUT) -> str:
    result = CliRunner().invoke(app, args)
    assert result.exit_code == status, result.output
    lines = result.stdout.splitlines()
    assert len(lines) == 1, result.stdout
    said = json.loads(lines[0])
    assert said == {"status": "refused", "exit_code": status, "error": said["error"]}
    assert said["error"] in result.stderr  # the same message on stderr
    return str(said["error"])


def test_json_commands_that_refuse_say_so_in_json(tmp_path: Path) -> None:
    missing = tmp_path / "missing.csv"
    assert str(missing) in _refused(["estimate", "--json", str(missing)])
    run = ["run", "--json", "--port", NO_PORT, "--robot", str(NOMAD), "--measure", "fake"]
    error = _refused([*run, "--plan", "k=1,l=1,n=10,m=2", "--session", str(tmp_path / "a")])
    assert "unknown key 'm'" in error
    assert error.endswith("nothing moved")
    sock = ["--truth-socket", str(tmp_path / "t.sock"), "--session", str(tmp_path / "b")]
    # a failed pre-flight check of the error class (the port): exit 1, said the same way
    assert NO_PORT in _refused([*run, "--plan", "k=1,l=1,n=10", *sock], EXIT_ERROR)
    validate = ["validate", "--json", str(missing), "--path", "square:1"]
    assert "--alpha" in _refused([*validate, "--alpha", "2"])
    assert "--bogus" in _refused([*validate, "--bogus"])  # typer's own usage error
    assert not (tmp_path / "a").exists()
    assert not (tmp_path / "b").exists()


def test_without_json_stdout_stays_empty(tmp_path: Path) -> None:
    result = CliRunner().invoke(app, ["estimate", str(tmp_path / "missing.csv")])
    assert result.exit_code == EXIT_BAD_INPUT
    assert result.stdout == ""
