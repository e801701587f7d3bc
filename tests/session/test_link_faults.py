"""``odohil run`` against ``odohil emulate`` with link faults, as a user would run
it: a noise line must not hang it, a stray packet must not end the session, and a
stale reply must never be used (issue 9, item 3). The runs are processes, whose
timeout turns a hang into a failure, forked from a server that imported odohil
once (tests/forked.py: no 2 s start-up each); the pre-flight refusal of legs below the
wire's resolution runs in process (typer's CliRunner: nothing is sent)."""

from __future__ import annotations

import json
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from typer.testing import CliRunner

from fakes.nomad.process import EmulatorProcess
from odohil.cli.app import app
from odohil.cli.exit_codes import EXIT_ERROR, EXIT_STOP_UNCONFIRMED
from odohil.session.journal import events as ev
from odohil.session.journal.file import read_journal
from tests import forked
from tests.session.helpers import write_robot

EMULATOR = ["--time-scale", "20000", "--seed", "5"]
PLAN = "k=1,l=0.5,n=3;k=0.5,l=0.5,n=3"
BOUND_S = 60.0
"""No run here may take longer (wall s): the subprocess timeout that turns a hang
into a failure."""


FEW_TRIALS = "fewer than 10 trials a design, the planner's minimum for honest intervals"
"""The verdict's one reason for these six-trial sessions."""


def _emulator(tmp_path: Path, *extra: str) -> EmulatorProcess:
    return EmulatorProcess([*EMULATOR, *extra, "--truth-socket", str(tmp_path / "t.sock")])


class Done:
    """What a finished process left: exit status, stdout, stderr."""

    def __init__(self, returncode: int, stdout: str, stderr: str) -> None:
        self.returncode, self.stdout, self.stderr = returncode, stdout, stderr


def _forked(args: list[str]) -> Done:
    """``odohil ARGS`` as a process of its own (tests/forked.py), bounded by BOUND_S."""
    return Done(*forked.run(args, BOUND_S))


def _run(emulator: EmulatorProcess, tmp_path: Path) -> Done:
    args = [
        "run", "--allow-few-trials",
        "--port", emulator.device,
        "--truth-socket", emulator.truth_socket,
        "--robot", str(write_robot(tmp_path)),
        "--plan", PLAN,
        "--measure", "fake",
        "--session", str(tmp_path / "session"),
        "--seed", "2",
        "--json",
    ]  # fmt: skip
    return _forked(args)


def _records(tmp_path: Path) -> list[tuple[str, dict[str, Any]]]:
    try:
        contents = read_journal(tmp_path / "session")
    except Exception:
        return []
    return [(r.kind, dict(r.data)) for r in contents.records]


@pytest.fixture
def noise_from_start(tmp_path: Path) -> Iterator[EmulatorProcess]:
    with _emulator(tmp_path, "--fault", "noise") as process:
        yield process


def test_a_noise_line_at_connect_is_refused_in_bounded_time(
    noise_from_start: EmulatorProcess, tmp_path: Path
) -> None:
    started = time.monotonic()
    done = _run(noise_from_start, tmp_path)
    elapsed = time.monotonic() - started
    # a port that does not answer the protocol fails the pre-flight: an error (1),
    # not bad input; nothing moved
    assert done.returncode == EXIT_ERROR, (done.returncode, done.stderr)
    assert elapsed < 20.0, elapsed
    assert "not the robot's protocol" in done.stderr, done.stderr
    assert noise_from_start.device in done.stderr, done.stderr
    assert not any(kind == ev.SOLVED for kind, _ in _records(tmp_path))


def test_noise_that_starts_mid_motion_ends_the_run_in_bounded_time(tmp_path: Path) -> None:
    with _emulator(tmp_path, "--fault", "noise:pr@5") as emulator:
        started = time.monotonic()
        done = _run(emulator, tmp_path)
        elapsed = time.monotonic() - started
    # the noise goes on, so the robot's stop cannot be confirmed either (4)
    assert done.returncode == EXIT_STOP_UNCONFIRMED, (done.returncode, done.stderr)
    assert "the robot may still be moving" in done.stderr, done.stderr
    assert elapsed < 30.0, elapsed
    assert "not the robot's protocol" in done.stderr, done.stderr
    records = _records(tmp_path)
    solved = [data["trial"] for kind, data in records if kind == ev.SOLVED]
    voided = [data["trial"] for kind, data in records if kind == ev.VOID]
    # trials before the noise are kept; the one it hit is void, none after it ran
    assert len(voided) == 1, records
    assert solved == list(range(1, voided[0])), records


@pytest.mark.slow
@pytest.mark.parametrize("fault", ["merge", "merge:pr@2"])
def test_a_stray_packet_on_a_paced_line_does_not_end_the_session(
    fault: str, tmp_path: Path
) -> None:
    with _emulator(tmp_path, "--fault", fault) as emulator:
        done = _run(emulator, tmp_path)
        fired = emulator.truth().faults_fired
    assert fired, "the fault never fired"
    # the session completes: the six trials of the emulator at seed 5, tape seed 2
    # (doubtful for being below the planner's minimum trials a design, nothing else)
    result = json.loads(done.stdout)
    assert (done.returncode, result["verdict"]["status"]) == (3, "doubtful"), done.stderr
    assert [r.split(":")[0] for r in result["verdict"]["reasons"]] == [FEW_TRIALS]
    assert result["n_trials"] == 6
    solved = [data["trial"] for kind, data in _records(tmp_path) if kind == ev.SOLVED]
    assert sorted(solved) == [1, 2, 3, 4, 5, 6]


@pytest.mark.slow
def test_a_stale_reply_is_never_used(tmp_path: Path) -> None:
    # gs 12 is answered 1 s after the host's wait ran out: the failed gs voids
    # the trial and ends the run (1). The resume that follows at once finds gs 16
    # unanswered and ends the same way (1); the late reply to 12 arrives meanwhile,
    # in its drain, gs 13's wait or gs 16's, and is discarded
    # (tests/driver/test_link_safety.py times each case exactly): used as gs 16's
    # reply, that resume would go on and finish. The second resume finishes (3).
    with _emulator(tmp_path, "--fault", "late:gs@12", "--fault", "drop:gs@16") as emulator:
        done = _run(emulator, tmp_path)
        assert done.returncode == EXIT_ERROR, done.stderr
        assert "no reply within 1 s" in done.stderr, done.stderr
        resume = ["resume", str(tmp_path / "session"), "--json", "--from-here"]
        done = _forked(resume)
        assert done.returncode == EXIT_ERROR, done.stderr
        assert "no reply within 1 s" in done.stderr, done.stderr
        done = _forked(resume)
        fired = emulator.truth().faults_fired
    # the six trials at these seeds, two attempts voided
    # (doubtful for being below the planner's minimum trials a design, nothing else)
    verdict = json.loads(done.stdout)["verdict"]
    assert (done.returncode, verdict["status"]) == (3, "doubtful"), done.stderr
    assert [r.split(":")[0] for r in verdict["reasons"]] == [FEW_TRIALS]
    assert "late on gs" in fired, fired
    assert "drop on gs" in fired, fired
    records = _records(tmp_path)
    solved = sorted(data["trial"] for kind, data in records if kind == ev.SOLVED)
    assert solved == [1, 2, 3, 4, 5, 6]
    # the robot's clock as the journal saw it: each trial's zeroed sample, then its
    # trajectory (times relative to its first sample): it never goes backwards
    zeroed = [d["zeroed"]["robot_time_s"] for k, d in records if k == ev.TRIAL_START]
    assert zeroed == sorted(zeroed), zeroed
    for kind, data in records:
        if kind == ev.MOTION_DONE:
            times = [row[0] for row in data["trajectory"]]
            assert times == sorted(times), times
            assert times[0] == 0.0, times


def test_legs_below_the_wire_resolution_never_make_valid_trials(tmp_path: Path) -> None:
    with _emulator(tmp_path, "--no-pacing") as emulator:
        args = [
            "run", "--allow-few-trials",
            "--port", emulator.device,
            "--truth-socket", emulator.truth_socket,
            "--robot", str(write_robot(tmp_path)),
            "--plan", "k=1,l=0.001,n=3;k=0.5,l=0.001,n=3",
            "--measure", "fake",
            "--session", str(tmp_path / "session"),
            "--json",
        ]  # fmt: skip
        done = CliRunner().invoke(app, args)
        log = emulator.truth().motion_log
    # refused at pre-flight: bad input, no session, nothing sent
    assert done.exit_code == 2, done.stderr
    assert "--plan" in done.stderr, done.stderr
    assert "at least" in done.stderr, done.stderr
    assert not (tmp_path / "session").exists()
    assert not [r for r in log if r.command == "pr"], log
