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
from odohil.cli.exit_codes import EXIT_ERROR

JOURNALS = Path(__file__).resolve().parents[1] / "session" / "data" / "journals"
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
