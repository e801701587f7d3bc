"""The signal matrix: SIGINT, SIGTERM, SIGHUP and SIGQUIT at the start of a
motion, in the middle of it and while the distances are being measured.

Against ``odohil emulate`` at time scale 1 (motions take seconds of wall time),
through its truth socket: the robot is still within 0.5 s of odohil's exit and
does not move afterwards, the command exits 128 + N, the journal is
consistent (the attempt cut off during its motion is void, the one being
measured stays open), and a resume completes the session with every trial once.
Motion cases run ``odohil run --measure fake``; measurement cases run the
wizard in a pseudo-terminal, whose distance prompt really waits.
"""

from __future__ import annotations

import json
import signal
import subprocess
import time
from collections.abc import Iterator
from pathlib import Path

import pexpect
import pytest

from fakes.nomad.process import EmulatorProcess
from fakes.nomad.truth import TruthClient
from odohil.session import state as ev
from odohil.session.journal import read_journal
from odohil.session.state import Phase, SessionState, replay
from tests.session.helpers import FINE_TAPE_ROBOT_TOML
from tests.session.test_safety import ODOHIL, PARAMS, _still_after_exit, _wait_for
from tests.wizard.test_wizard import _marks, _prompt, _spawn, _type_all

SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP, signal.SIGQUIT)
RUN_PLAN = "k=0.5,l=0.2,n=2"
"""Two one-way 0.2 m trials (about 1.3 s of motion each): the fewest that estimate."""
WIZARD_PLAN = "k=0.5,l=0.2,n=1"


@pytest.fixture(scope="module")
def emulator(tmp_path_factory: pytest.TempPathFactory) -> Iterator[EmulatorProcess]:
    sock = str(tmp_path_factory.mktemp("matrix") / "t.sock")
    with EmulatorProcess(
        [*PARAMS, "--seed", "7", "--time-scale", "1", "--truth-socket", sock]
    ) as process:
        yield process


def _reason(signum: int) -> str:
    return "interrupted" if signum == signal.SIGINT else signal.Signals(signum).name


def _consistent(folder: Path, signum: int) -> SessionState:
    records = read_journal(folder).records
    state = replay(records)  # raises on an inconsistent journal
    assert records[-1].kind == ev.STOPPED
    assert records[-1].data["reason"] == _reason(signum)
    assert records[-1].data["robot"] == "stopped"
    assert not state.finished
    return state


def _every_trial_once(folder: Path, n_trials: int) -> None:
    records = read_journal(folder).records
    assert replay(records).finished
    solved = [r.data["trial"] for r in records if r.kind == ev.SOLVED]
    assert solved == list(range(1, n_trials + 1))


@pytest.mark.slow
def test_every_signal_at_every_step_stops_the_robot_and_resumes(
    emulator: EmulatorProcess, tmp_path: Path
) -> None:
    robot = tmp_path / "robot.toml"
    robot.write_text(FINE_TAPE_ROBOT_TOML)
    for signum in SIGNALS:
        for moment in ("motion start", "mid-motion"):
            _motion_case(emulator, tmp_path, robot, signum, moment)
        _measurement_case(emulator, tmp_path, robot, signum)


def _motion_case(
    emulator: EmulatorProcess, tmp_path: Path, robot: Path, signum: int, moment: str
) -> None:
    case = f"{signal.Signals(signum).name} at {moment}"
    folder = tmp_path / case.replace(" ", "-")
    command = [
        ODOHIL, "run", "--allow-few-trials",
                "--port", emulator.device, "--truth-socket", emulator.truth_socket,
        "--robot", str(robot), "--plan", RUN_PLAN, "--measure", "fake",
        "--session", str(folder), "--json",
    ]  # fmt: skip
    process = subprocess.Popen(
        command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True
    )
    _wait_for(process, folder, ev.MOTION_START, 30)
    if moment == "mid-motion":
        time.sleep(0.3)
        assert emulator.truth().moving, case
    process.send_signal(signum)
    _, err = process.communicate(timeout=30)
    exited_at = time.monotonic()
    assert process.returncode == 128 + signum, (case, err)
    _still_after_exit(emulator, exited_at)
    assert "robot stopped" in err, (case, err)
    state = _consistent(folder, signum)
    records = read_journal(folder).records
    assert [(r.data["trial"], r.data["attempt"]) for r in records if r.kind == ev.VOID] == [
        (1, 1)
    ], case
    assert state.open_trial is None, case
    resumed = subprocess.run(
        [ODOHIL, "resume", str(folder), "--json", "--from-here"],
        capture_output=True,
        text=True,
        timeout=60,
    )
    # a two-trial session cannot pin four parameters: its estimate may be judged untrusted (3)
    assert resumed.returncode in (0, 3), (case, resumed.stderr)
    result = json.loads(resumed.stdout)
    assert result["n_trials"] == 2
    assert resumed.returncode == 0 or result["verdict"]["reasons"], (case, result["verdict"])
    _every_trial_once(folder, 2)


def _measurement_case(emulator: EmulatorProcess, tmp_path: Path, robot: Path, signum: int) -> None:
    case = f"{signal.Signals(signum).name} while measuring"
    folder = tmp_path / case.replace(" ", "-")
    with TruthClient(emulator.truth_socket) as truth:
        child = _spawn(["--port", emulator.device, "--robot", str(robot),
                        "--plan", WIZARD_PLAN, "--session", str(folder)])  # fmt: skip
        values = _marks(child, truth)
        child.expect(_prompt(0))
        child.kill(signum)
        child.expect(pexpect.EOF)
        child.wait()
        exited_at = time.monotonic()
        assert child.exitstatus == 128 + signum, (case, child.before)
        _still_after_exit(emulator, exited_at)
        state = _consistent(folder, signum)
        assert state.open_trial is not None, case
        assert state.open_trial.phase is Phase.MEASURING, case
        # the wizard again on the session: the distances, and the session is done
        child = _spawn(["--port", emulator.device, "--session", str(folder)])
        child.expect(_prompt(0))
        _type_all(child, values, "Trial 1 solved")
        child.expect(pexpect.EOF)
        child.wait()
        # one trial gives no estimate: the wizard says so and exits 3 (not trusted)
        assert child.exitstatus == 3, (case, child.before)
    _every_trial_once(folder, 1)
