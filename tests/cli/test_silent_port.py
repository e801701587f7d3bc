"""Issue 31: a port that opens but where nothing answers (a pty with nobody on
the other end, a ``socket://`` listener that never replies) exits 1 from every
command that opens a robot, for both robots, with one message naming the
robot, the port and its rate, and what to check (odohil/driver/port.py
``no_answer``). In process; each robot's connect waits its own documented
time (about 2 s) for the answer that never comes."""

from __future__ import annotations

import os
import shutil
import socket
import tty
from collections.abc import Iterator
from pathlib import Path

import pytest
from typer.testing import CliRunner, Result

from odohil.cli.app import app
from odohil.cli.exit_codes import EXIT_BAD_INPUT, EXIT_ERROR
from odohil.session.journal import events as ev
from odohil.session.journal.file import read_journal

JOURNALS = Path(__file__).resolve().parents[1] / "session" / "data" / "journals"
ROBOTS = Path(__file__).resolve().parents[2] / "odohil" / "robots"
LABELS = {"nomad150": "Nomad 150", "create2": "iRobot Create 2"}
RATES = {"nomad150": 38400, "create2": 115200}


@pytest.fixture
def silent_pty() -> Iterator[str]:
    """A pty whose robot end is held open and never read or written."""
    master, slave = os.openpty()
    tty.setraw(slave)
    try:
        yield os.ttyname(slave)
    finally:
        os.close(slave)
        os.close(master)


@pytest.fixture
def silent_socket() -> Iterator[str]:
    """A TCP listener that never accepts (the kernel completes the connection)."""
    with socket.socket() as listener:
        listener.bind(("127.0.0.1", 0))
        listener.listen(4)
        yield f"socket://127.0.0.1:{listener.getsockname()[1]}"


def _trials(path: Path, k: float, l_m: float, n: int, *variants: str) -> Path:
    """A trial file of ``n`` rows of one design, its variants in turn (``turn``)."""
    cycle = variants or ("turn",)
    rows = [f"{k},{l_m},{cycle[i % len(cycle)]},0.01,0.0,0.0" for i in range(n)]
    path.write_text("k,l_m,variant,dx_m,dy_m,dtheta_rad\n" + "\n".join(rows) + "\n")
    return path


def _says_no_answer(result: Result, robot: str, port: str) -> None:
    text = " ".join(result.output.split())
    assert result.exit_code == EXIT_ERROR, text
    assert f"the {LABELS[robot]} on {port} does not answer at {RATES[robot]} baud" in text
    assert "check that" in text
    assert "nothing" in text  # nothing moved


def _invoke(*args: str | Path) -> Result:
    return CliRunner().invoke(app, [str(a) for a in args])


def test_every_command_that_opens_a_robot_exits_1_on_a_silent_port(
    tmp_path: Path, silent_pty: str, silent_socket: str
) -> None:
    # each command once; each robot on each kind of silent port at least once
    run = _invoke(
        "run", "--port", silent_socket, "--robot", "create2", "--plan", "k=0.5,l=1,n=2",
        "--allow-few-trials", "--session", tmp_path / "c", "--measure",
        _trials(tmp_path / "c.csv", 0.5, 1, 2, "reverse", "reverse-backward"),
    )  # fmt: skip
    _says_no_answer(run, "create2", silent_socket)
    assert not (tmp_path / "c").exists()
    session = shutil.copytree(JOURNALS / "interrupted", tmp_path / "interrupted")
    resumed = _invoke(
        "resume", session, "--port", silent_socket,
        "--measure", _trials(tmp_path / "r.csv", 1, 0.5, 4),
    )  # fmt: skip
    _says_no_answer(resumed, "nomad150", silent_socket)
    calibration = shutil.copytree(JOURNALS / "finished", tmp_path / "finished")
    validated = _invoke(
        "validate", calibration, "--path", "forth-back:2,1", "--trials", "10", "--force",
        "--port", silent_pty, "--measure", _trials(tmp_path / "v.csv", 2, 1, 10),
    )  # fmt: skip
    _says_no_answer(validated, "nomad150", silent_pty)
    wizard = _invoke(
        "wizard", "--port", silent_pty, "--robot", "create2", "--plan", "k=0.5,l=1,n=10",
        "--session", tmp_path / "w",
    )  # fmt: skip
    _says_no_answer(wizard, "create2", silent_pty)
    assert not (tmp_path / "w").exists()


def _robot_with_timeout(tmp_path: Path, robot: str, timeout: str) -> Path:
    """The built-in description of ``robot`` with ``[serial] timeout_s = timeout``."""
    text = (ROBOTS / f"{robot}.toml").read_text(encoding="utf-8")
    if "[serial]" not in text:
        text += "\n[serial]\n"
    path = tmp_path / f"{robot}-timeout.toml"
    path.write_text(text.replace("[serial]\n", f"[serial]\ntimeout_s = {timeout}\n"), "utf-8")
    return path


def _run_args(tmp_path: Path, robot: Path, port: str) -> list[str | Path]:
    create2 = "create2" in robot.name
    variants = ("reverse", "reverse-backward") if create2 else ("turn", "turn-backward")
    trials = _trials(tmp_path / "t.csv", 0.5, 1, 2, *variants)
    return [
        "run", "--port", port, "--robot", robot, "--plan", "k=0.5,l=1,n=2",
        "--allow-few-trials", "--session", tmp_path / "s", "--measure", trials,
    ]  # fmt: skip


@pytest.mark.parametrize("robot", ["nomad150", "create2"])
def test_the_descriptions_serial_timeout_is_the_drivers_reply_timeout(
    tmp_path: Path, silent_socket: str, robot: str
) -> None:
    # [serial] timeout_s = 0.1 on a port where nothing answers: the connect gives
    # up after 0.1 s waits (each backend's default is 1 s, and its connect waits
    # at least 2 s in all), and says so; the Create 2 keeps its 1 s wait after open
    # (the driver's message names the wait it used; no wall-time bound: a loaded
    # machine stretches any, and tests assert no timings)
    path = _robot_with_timeout(tmp_path, robot, "0.1")
    result = _invoke(*_run_args(tmp_path, path, silent_socket))
    _says_no_answer(result, robot, silent_socket)
    assert "within 0.1 s" in " ".join(result.output.split())
    assert not (tmp_path / "s").exists()


@pytest.mark.parametrize("robot", ["nomad150", "create2"])
@pytest.mark.parametrize("timeout", ["0.001", "61", "0"])
def test_a_serial_timeout_out_of_the_backends_range_exits_2(
    tmp_path: Path, robot: str, timeout: str
) -> None:
    path = _robot_with_timeout(tmp_path, robot, timeout)
    result = _invoke(*_run_args(tmp_path, path, "/nonexistent/tty-odohil"))
    text = " ".join(result.output.split())
    assert result.exit_code == EXIT_BAD_INPUT, text
    assert "serial.timeout_s must be at least 0.05 and at most 60 s" in text
    assert "cannot open" not in text  # refused before the port was tried
    assert not (tmp_path / "s").exists()


def test_a_resume_whose_port_does_not_answer_journals_no_resume(tmp_path: Path) -> None:
    # a missing port and a silent one: exit 1, nothing moved, and the journal's
    # records are those it had (no `resumed` record for a resume that never happened)
    session = shutil.copytree(JOURNALS / "interrupted", tmp_path / "interrupted")
    before = read_journal(session).records
    resumed = _invoke(
        "resume", session, "--port", "/nonexistent/tty-odohil",
        "--measure", _trials(tmp_path / "r.csv", 1, 0.5, 4),
    )  # fmt: skip
    text = " ".join(resumed.output.split())
    assert resumed.exit_code == EXIT_ERROR, text
    assert "cannot open '/nonexistent/tty-odohil'" in text
    after = read_journal(session).records
    assert after == before
    assert [r.kind for r in after].count(ev.RESUMED) == [r.kind for r in before].count(ev.RESUMED)
