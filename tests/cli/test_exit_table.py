"""One exit table for every command (issue 18): the same pre-flight failure
exits with the same status from every command that runs a session."""

from __future__ import annotations

from pathlib import Path

from typer.testing import CliRunner

from odohil.cli.app import app
from odohil.cli.exit_codes import EXIT_ERROR
from odohil.robots import __file__ as robots_init

NOMAD = Path(robots_init).with_name("nomad150.toml")
NO_PORT = "/dev/odohil-no-such-port"
PLAN = "k=1,l=1,n=10"


def test_a_port_that_does_not_answer_exits_1_from_run_and_wizard(tmp_path: Path) -> None:
    """`run` exited 1 (an error: the port does not answer) while the wizard
    exited 2 (bad input) for the same failed check; both now exit by the
    check's class, as odohil/cli/exit_codes.py says."""
    runner = CliRunner()
    common = ["--port", NO_PORT, "--robot", str(NOMAD), "--plan", PLAN]
    fake = ["--measure", "fake", "--truth-socket", str(tmp_path / "truth.sock")]
    run = runner.invoke(app, ["run", *common, *fake, "--session", str(tmp_path / "r")])
    wizard = runner.invoke(app, ["wizard", *common, "--session", str(tmp_path / "w")])
    statuses = (run.exit_code, wizard.exit_code)
    assert statuses == (EXIT_ERROR, EXIT_ERROR), (run.output, wizard.output)
    for result in (run, wizard):
        assert NO_PORT in result.output
        assert "nothing" in result.output  # nothing moved
    assert not (tmp_path / "r").exists()
    assert not (tmp_path / "w").exists()
