"""Every way out stops the robot, and odohil claims only what it checked.

Through the console commands against ``odohil emulate`` on a real pty; the
emulator's truth socket shows what the robot really did. Each command is a
process of its own, forked from a server that imported odohil once
(tests/forked.py), except the full-disk case (its file-size limit is set in a
console process) and the wizard.
"""

from __future__ import annotations

import os
import resource
import shutil
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from fakes.nomad.process import EmulatorProcess
from fakes.nomad.truth import TruthSnapshot
from odohil.driver.nomad.robot import NomadRobot
from odohil.errors import JournalError, StopUnconfirmedError
from odohil.session.journal import events as ev
from odohil.session.journal.file import JOURNAL_NAME, read_journal
from odohil.session.journal.state import replay
from odohil.session.plans.plan import parse_plan
from odohil.session.run.engine import start_session
from tests import forked
from tests.session.helpers import write_robot

ODOHIL = shutil.which("odohil") or "odohil"
PARAMS = ["--E-R", "-1", "--K-theta", "0.3", "--K-rho", "0.0009", "--no-pacing"]
MAY_STILL_MOVE = "the robot may still be moving: use its emergency stop"
SHORT_PLAN = "k=1,l=0.3,n=2"  # the fewest trials run accepts (two)


def _emulator(tmp_path: Path, name: str, *extra: str, time_scale: str = "1") -> EmulatorProcess:
    sock = str(tmp_path / f"{name}.sock")
    return EmulatorProcess([*PARAMS, "--time-scale", time_scale, "--truth-socket", sock, *extra])


def _run_args(emulator: EmulatorProcess, tmp_path: Path, plan: str, folder: Path) -> list[str]:
    return [
        ODOHIL, "run", "--allow-few-trials",
        "--port", emulator.device,
        "--truth-socket", emulator.truth_socket,
        "--robot", str(write_robot(tmp_path)),
        "--plan", plan,
        "--measure", "fake",
        "--session", str(folder),
        "--seed", "2",
        "--json",
    ]  # fmt: skip


def _kinds(folder: Path) -> list[str]:
    try:
        return [r.kind for r in read_journal(folder).records]
    except JournalError:  # not there yet
        return []


def _wait_for(
    process: subprocess.Popen[str] | forked.Forked, folder: Path, kind: str, timeout_s: float
) -> None:
    deadline = time.monotonic() + timeout_s
    while kind not in _kinds(folder):
        assert process.poll() is None, f"odohil ended before {kind}: {process.communicate()}"
        assert time.monotonic() < deadline, f"no {kind} record within {timeout_s} s"
        time.sleep(0.002)


def _still_after_exit(emulator: EmulatorProcess, exited_at: float) -> TruthSnapshot:
    """The robot is still within 0.5 s of odohil's exit and does not move afterwards."""
    while (snap := emulator.truth()).moving:
        assert time.monotonic() - exited_at < 0.5, "the robot still moves 0.5 s after the exit"
        time.sleep(0.01)
    time.sleep(0.3)
    later = emulator.truth()
    assert not later.moving
    assert (later.true_x_m, later.true_y_m) == (snap.true_x_m, snap.true_y_m)
    return later


# -- line cut -----------------------------------------------------------------


def _assert_unconfirmed(code: int, err: str, folder: Path) -> None:
    assert code == 4, err
    assert MAY_STILL_MOVE in err
    assert "robot stopped" not in err
    records = read_journal(folder).records
    assert records[-1].kind == ev.STOP_UNCONFIRMED
    assert records[-2].kind == ev.VOID
    state = replay(records)  # replay accepts the new record
    assert state.open_trial is None


def test_a_cut_line_is_reported_as_a_robot_that_may_still_move(tmp_path: Path) -> None:
    folder = tmp_path / "session"
    with _emulator(tmp_path, "cut", "--fault", "disconnect:pr@1") as emulator:
        started = time.monotonic()
        done = forked.completed(_run_args(emulator, tmp_path, SHORT_PLAN, folder), timeout=60)
        # the robot really drove on: odohil said so rather than "robot stopped"
        assert emulator.truth().moving or time.monotonic() - started > 2.0
    _assert_unconfirmed(done.returncode, done.stderr, folder)


def test_an_emulator_killed_mid_motion_is_a_robot_that_may_still_move(tmp_path: Path) -> None:
    folder = tmp_path / "session"
    with _emulator(tmp_path, "kill") as emulator:
        process = forked.start(_run_args(emulator, tmp_path, SHORT_PLAN, folder)[1:])
        with process:
            _wait_for(process, folder, ev.MOTION_START, 30)
            time.sleep(0.2)
            emulator.stop()
            _, err = process.communicate(timeout=30)
    _assert_unconfirmed(process.returncode, err, folder)


# -- a full disk ----------------------------------------------------------------


def _small_files() -> None:
    resource.setrlimit(resource.RLIMIT_FSIZE, (4096, 4096))


def test_a_journal_that_cannot_be_written_is_not_called_journaled(tmp_path: Path) -> None:
    folder = tmp_path / "session"
    with _emulator(tmp_path, "disk", time_scale="20000") as emulator:
        done = subprocess.run(
            _run_args(emulator, tmp_path, "k=1,l=0.3,n=20", folder),
            capture_output=True,
            text=True,
            timeout=120,
            preexec_fn=_small_files,
            # under the limit a bytecode cache would be cut at 4096 bytes and
            # still replace the good one (the raw write's short count goes
            # unchecked): every later odohil process would fail to import
            env={**os.environ, "PYTHONDONTWRITEBYTECODE": "1"},
        )
        assert not emulator.truth().moving
    assert done.returncode == 1, done.stderr
    assert "the journal could not be written" in done.stderr
    assert "journaled" not in done.stderr.replace("could not be written", "")
    assert "robot stopped" in done.stderr  # that one was checked: the robot reported it
    assert (folder / JOURNAL_NAME).stat().st_size <= 4096


# -- a busy session ---------------------------------------------------------------


@pytest.fixture
def spare(tmp_path: Path) -> Iterator[EmulatorProcess]:
    """A second robot that counts every gs it gets (its fault fires on the first)."""
    with _emulator(tmp_path, "spare", "--fault", "drop:gs@1", time_scale="20000") as emulator:
        yield emulator


def test_a_busy_session_is_refused_before_anything_is_sent(
    tmp_path: Path, spare: EmulatorProcess
) -> None:
    folder = tmp_path / "session"
    robot = write_robot(tmp_path)
    # the session as a running odohil holds it: created, journal open and locked
    journal, _ = start_session(
        folder, robot.read_text(), parse_plan(SHORT_PLAN), measure="fake", settings={}
    )
    commands = {
        "run": _run_args(spare, tmp_path, SHORT_PLAN, folder),
        "resume": [ODOHIL, "resume", str(folder), "--port", spare.device],
        "wizard": [sys.executable, "-m", "odohil", "wizard", "--port", spare.device,
                   "--robot", str(robot), "--plan", SHORT_PLAN, "--session", str(folder)],
    }  # fmt: skip
    with journal:
        for name, command in commands.items():
            refused = (
                forked.completed(command, timeout=60)
                if command[0] == ODOHIL
                else subprocess.run(command, capture_output=True, text=True, timeout=60)
            )
            output = " ".join((refused.stdout + refused.stderr).split())
            assert refused.returncode == 2, (name, output)
            assert "session in use" in output, (name, output)
    snap = spare.truth()
    assert snap.faults_fired == ()  # no gs reached the robot
    assert snap.motion_log == ()  # nor st, nor any motion
    assert [r.kind for r in read_journal(folder).records] == [ev.SESSION]


# -- the stop itself ------------------------------------------------------------


def test_stop_and_confirm_waits_until_the_robot_reports_standing_still(tmp_path: Path) -> None:
    with _emulator(tmp_path, "confirm") as emulator:
        robot = NomadRobot.connect(emulator.device)
        with robot:
            robot.set_speeds(0.5, 0.5, 0.5)
            robot.set_accelerations(0.5, 0.5, 0.5)
            robot.move_relative(0.5, 0.0)
            time.sleep(0.5)
            assert emulator.truth().moving
            asked = time.monotonic()
            sample = robot.stop_and_confirm(2.0)
            took = time.monotonic() - asked
            assert not sample.moving
            assert not emulator.truth().moving  # the robot's word matches the truth
            assert took < 2.0
        with pytest.raises(StopUnconfirmedError, match="closed"):
            robot.stop_and_confirm(2.0)  # after close: nothing to ask, said at once


def test_a_second_signal_during_the_stop_does_not_skip_it(tmp_path: Path) -> None:
    folder = tmp_path / "session"
    with _emulator(tmp_path, "twice") as emulator:
        with forked.start(_run_args(emulator, tmp_path, "k=0.5,l=0.5,n=2", folder)[1:]) as process:
            _wait_for(process, folder, ev.MOTION_START, 30)
            time.sleep(0.4)
            assert emulator.truth().moving
            process.send_signal(signal.SIGTERM)
            time.sleep(0.05)  # the robot is decelerating: the stop is under way
            process.send_signal(signal.SIGINT)
            _, err = process.communicate(timeout=30)
            exited_at = time.monotonic()
        assert process.returncode == 128 + signal.SIGTERM, err  # the first way out's status
        _still_after_exit(emulator, exited_at)
    records = read_journal(folder).records
    assert [r.kind for r in records][-2:] == [ev.VOID, ev.STOPPED]
    assert records[-1].data["reason"] == "SIGTERM"
