"""``odohil run --exclude``: the named trials are left out of the live and the
final estimate, the journal keeps them; a number outside the plan exits 2.

In process (typer's CliRunner on odohil.cli.app's app: the same parsing,
session and rendering as the console script) against the emulator on its pty."""

from __future__ import annotations

import json
from collections.abc import Iterator
from pathlib import Path

import pytest
from typer.testing import CliRunner, Result

from fakes.nomad.process import EmulatorProcess
from odohil.cli.app import app
from odohil.session.journal.state import ambiguous_trials, load_session
from tests.session.helpers import write_robot

PLAN = "k=1,l=0.5,n=4;k=0.5,l=0.5,n=4"


@pytest.fixture
def emulator(tmp_path: Path) -> Iterator[EmulatorProcess]:
    args = ["--time-scale", "20000", "--seed", "5", "--no-pacing"]
    with EmulatorProcess([*args, "--truth-socket", str(tmp_path / "t.sock")]) as process:
        yield process


def _run(emulator: EmulatorProcess, tmp_path: Path, exclude: str) -> Result:
    command = [
        "run", "--allow-few-trials",
        "--port", emulator.device,
        "--truth-socket", emulator.truth_socket,
        "--robot", str(write_robot(tmp_path)),
        "--plan", PLAN,
        "--measure", "fake",
        "--session", str(tmp_path / "session"),
        "--exclude", exclude,
        "--seed", "2",
        "--json",
    ]  # fmt: skip
    return CliRunner().invoke(app, command)


def test_excluded_trials_are_left_out_but_journaled(
    emulator: EmulatorProcess, tmp_path: Path
) -> None:
    done = _run(emulator, tmp_path, "2,7")
    # the six trials left at these seeds (emulator 5, tape 2): doubtful only for
    # being below the planner's minimum trials a design (the exclusion is the point)
    verdict = json.loads(done.stdout)["verdict"]
    assert (done.exit_code, verdict["status"]) == (3, "doubtful"), done.stderr
    assert [r.split(":")[0] for r in verdict["reasons"]] == [
        "fewer than 10 trials a design, the planner's minimum for honest intervals"
    ]
    result = json.loads(done.stdout)
    assert result["excluded"] == [2, 7]
    state = load_session(tmp_path / "session").state
    assert sorted(t.trial for t in state.completed) == list(range(1, 9))
    ambiguous = {t.trial for t in ambiguous_trials(state)} - {2, 7}
    assert result["n_trials"] == 6 - len(ambiguous)
    assert {2, 7}.isdisjoint(t["trial"] for t in result["trials"])


def test_exclude_outside_the_plan_exits_2(emulator: EmulatorProcess, tmp_path: Path) -> None:
    done = _run(emulator, tmp_path, "9")
    assert done.exit_code == 2
    assert "--exclude" in done.stderr
    assert "1..8" in done.stderr
    assert not (tmp_path / "session").exists()
