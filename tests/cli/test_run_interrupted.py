"""An interrupted ``odohil run --json`` prints one JSON object with its status
and the partial estimate; no exception class name reaches the operator or the
journal (issue 11, item 7). Against ``odohil emulate`` on a pseudo-terminal."""

from __future__ import annotations

import json
import signal
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from fakes.nomad.process import EmulatorProcess
from odohil.session.journal import events as ev
from odohil.session.journal.file import journal_path, read_journal
from tests import forked
from tests.session.helpers import FINE_TAPE_ROBOT_TOML
from tests.session.test_safety import PARAMS

CLASS_NAMES = ("KeyboardInterrupt", "SignalReceived", "Traceback")


@pytest.fixture(scope="module")
def emulator(tmp_path_factory: pytest.TempPathFactory) -> Iterator[EmulatorProcess]:
    sock = str(tmp_path_factory.mktemp("interrupted") / "t.sock")
    with EmulatorProcess(
        [*PARAMS, "--seed", "3", "--time-scale", "4", "--truth-socket", sock]
    ) as e:
        yield e


def _solved(folder: Path) -> int:
    try:
        return sum(1 for r in read_journal(folder).records if r.kind == ev.SOLVED)
    except Exception:  # the journal is being created
        return 0


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_an_interrupted_json_run_prints_its_status_and_partial_estimate(
    emulator: EmulatorProcess, tmp_path: Path, signum: int
) -> None:
    robot = tmp_path / "robot.toml"
    robot.write_text(FINE_TAPE_ROBOT_TOML)
    folder = tmp_path / "session"
    # a process of its own, forked from a server that imported odohil once (tests/forked.py)
    process = forked.start(
        [
            "run",
            "--allow-few-trials",
            "--port",
            emulator.device,
            "--truth-socket",
            emulator.truth_socket,
            "--robot",
            str(robot),
            "--plan",
            "k=0.5,l=0.2,n=12",
            "--measure",
            "fake",
            "--session",
            str(folder),
            "--json",
        ],
    )
    deadline = time.monotonic() + 60
    while _solved(folder) < 3:
        assert process.poll() is None, process.communicate()
        assert time.monotonic() < deadline, "no 3 solved trials within 60 s"
        time.sleep(0.01)
    process.send_signal(signum)
    out, err = process.communicate(timeout=30)
    process.close()
    assert process.returncode == 128 + signum, err
    # before: nothing at all on stdout
    document = json.loads(out)  # one object, nothing else
    assert document["status"] == "interrupted"
    assert document["signal"] == signal.Signals(signum).name
    assert document["stop_confirmed"] is True
    assert document["journaled"] is True
    assert document["trials_done"] >= 3
    partial = document["partial_estimate"]
    assert partial is not None, document.get("partial_estimate_note")
    assert partial["n_trials"] == document["trials_done"]
    assert set(partial["parameters"]) == {"E_R", "E_T", "K_theta", "K_rho"}
    journal = journal_path(folder).read_text()
    for name in CLASS_NAMES:  # before: "KeyboardInterrupt" in the journal and on stderr
        assert name not in out
        assert name not in err
        assert name not in journal
    expected = "Ctrl-C" if signum == signal.SIGINT else "SIGTERM received"
    assert f"interrupted ({expected})" in err
    assert read_journal(folder).records[-1].data["message"] == expected
