"""Setting a session up (issue 18): nothing is written before pre-flight
passes, a resumed session's plan is not silently swapped for another, and a
--session that is a dangling symbolic link is called what it is. The wizard
and run in process through typer's runner; they fail before any prompt."""

from __future__ import annotations

from pathlib import Path

from typer.testing import CliRunner, Result

from odohil.cli.app import app
from odohil.robots import __file__ as robots_init
from odohil.session.journal.file import read_journal
from odohil.session.plans.plan import parse_plan
from odohil.session.run.engine import start_session

NOMAD = Path(robots_init).with_name("nomad150.toml")
NO_PORT = "/dev/odohil-no-such-port"


def invoke(*args: str | Path) -> Result:
    return CliRunner().invoke(app, [str(a) for a in args])


def flat(result: Result) -> str:
    return " ".join(result.output.split())


def test_a_wizard_that_fails_pre_flight_leaves_no_session(tmp_path: Path) -> None:
    folder = tmp_path / "hallway"
    result = invoke(
        "wizard", "--port", NO_PORT, "--robot", NOMAD,
        "--plan", "k=1,l=6,n=30;k=20,l=0.5,n=30", "--session", folder,
    )  # fmt: skip
    assert result.exit_code == 1, result.output  # the port does not answer: as `run` exits
    assert "nothing was moved" in flat(result)
    assert not folder.exists()  # not even the plan


def test_a_resumed_session_with_another_plan_is_refused(tmp_path: Path) -> None:
    folder = tmp_path / "hallway"
    toml = NOMAD.read_text(encoding="utf-8")
    journal, _ = start_session(
        folder, toml, parse_plan("k=1,l=6,n=30;k=20,l=0.5,n=30"), measure="operator",
        settings={"port": NO_PORT}, robot_path=str(NOMAD),
    )  # fmt: skip
    journal.close()
    before = read_journal(folder).records
    result = invoke("wizard", "--port", NO_PORT, "--plan", "k=4,l=0.5,n=10", "--session", folder)
    assert result.exit_code == 2, result.output
    words = flat(result)
    assert "--plan k=4,l=0.5,n=10 differs from the session's plan" in words, words
    assert "k=1,l=6,n=30" in words
    assert read_journal(folder).records == before
    # the session's own plan (or none) resumes it: it gets as far as the port
    same = invoke("wizard", "--port", NO_PORT, "--plan", "k=1,l=6,n=30;k=20,l=0.5,n=30",
                  "--session", folder)  # fmt: skip
    assert "differs" not in flat(same)
    assert "robot answers" in flat(same)


def test_a_dangling_symlink_session_is_named_as_such(tmp_path: Path) -> None:
    link = tmp_path / "hallway"
    link.symlink_to(tmp_path / "gone")
    for command in (
        ("wizard", "--port", NO_PORT, "--robot", NOMAD, "--plan", "k=1,l=1,n=10"),
        ("run", "--port", NO_PORT, "--robot", NOMAD, "--plan", "k=1,l=1,n=10", "--measure", "fake"),
    ):
        result = invoke(*command, "--session", link)
        assert result.exit_code == 2, result.output
        words = flat(result)
        assert "symbolic link" in words, words
        assert "already holds a session journal" not in words
    assert not (tmp_path / "gone").exists()
