"""The guardian (odohil/driver/guardian.py): the robot's stop when the driving
process dies (kill -9, which is also what the out-of-memory killer sends, or an
interpreter crash), and not one byte while it lives.

A real process opens a real pty or ``socket://`` line and starts a guardian,
as a backend's ``arm`` does; the test holds the other end of the line and
kills the process (the process is the point: kill -9 cannot be caught).
"""

from __future__ import annotations

import os
import resource
import select
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager

import pytest

import fakes
from odohil.driver.guardian import line_fd, start_guardian
from odohil.driver.port import open_serial_url
from odohil.errors import SafetyError

STOP = bytes.fromhex("0102030405")
"""Stand-in stop bytes: the guardian sends whatever the backend declares."""

CHILD = """
import sys
from odohil.driver.guardian import start_guardian
from odohil.driver.port import open_serial_url

port = open_serial_url(sys.argv[1], 115200)
guardian = start_guardian(port, bytes.fromhex(sys.argv[2]))
print("ready", guardian.pid, flush=True)
for line in sys.stdin:
    if line.strip() == "release":
        guardian.release()
        port.close()
        print("released", flush=True)
    elif line.strip() == "crash":
        import ctypes

        ctypes.string_at(0)  # a segmentation fault: the interpreter crashes
"""


def _alive(pid: int) -> bool:
    """Whether ``pid`` runs (a zombie does not count)."""
    try:
        with open(f"/proc/{pid}/stat", encoding="ascii") as stat:
            return stat.read().rsplit(")", 1)[1].split()[0] != "Z"
    except FileNotFoundError:
        return False


def _read_for(fd: int, seconds: float) -> bytes:
    """What arrives on ``fd`` within ``seconds``."""
    got = b""
    deadline = time.monotonic() + seconds
    while (left := deadline - time.monotonic()) > 0:
        if select.select([fd], [], [], left)[0]:
            try:
                chunk = os.read(fd, 4096)
            except OSError:  # a pty's master reads EIO once every slave is closed
                break
            if not chunk:
                break
            got += chunk
    return got


def _no_core_dump() -> None:
    """A crash's core dump delays the kernel's closing of its descriptors (and so
    the stop) by as long as it takes to write; none here."""
    resource.setrlimit(resource.RLIMIT_CORE, (0, 0))


@contextmanager
def _driver(url: str) -> Iterator[tuple[subprocess.Popen[str], int]]:
    """A process that opens ``url`` and starts a guardian; (it, the guardian's pid)."""
    child = subprocess.Popen(
        [sys.executable, "-c", CHILD, url, STOP.hex()],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
        preexec_fn=_no_core_dump,
    )
    try:
        assert child.stdout is not None
        word, pid = child.stdout.readline().split()
        assert word == "ready"
        yield child, int(pid)
    finally:
        if child.poll() is None:
            child.kill()
        child.wait()


@contextmanager
def _pty() -> Iterator[tuple[str, int]]:
    master, slave = os.openpty()
    try:
        yield os.ttyname(slave), master
    finally:
        os.close(master)
        os.close(slave)


@contextmanager
def _tcp() -> Iterator[tuple[str, Callable[[], int]]]:
    server = socket.create_server(("127.0.0.1", 0))
    accepted: list[socket.socket] = []

    def accept() -> int:
        if not accepted:
            server.settimeout(10)
            accepted.append(server.accept()[0])
        return accepted[0].fileno()

    try:
        yield f"socket://127.0.0.1:{server.getsockname()[1]}", accept
    finally:
        for conn in accepted:
            conn.close()
        server.close()


def _gone_within(pid: int, seconds: float) -> bool:
    deadline = time.monotonic() + seconds
    while _alive(pid):
        if time.monotonic() > deadline:
            return False
        time.sleep(0.01)
    return True


def _kill_and_expect_stop(
    child: subprocess.Popen[str], guardian: int, line: int, how: str = "kill -9"
) -> float:
    """Silent while the driver lives; the stop within 0.5 s of kill -9 (or a
    crash); the guardian gone. The time from the kill to the stop bytes, s."""
    assert _read_for(line, 0.3) == b""  # the driver lives: not a byte
    killed = time.monotonic()
    if how == "kill -9":
        child.send_signal(signal.SIGKILL)
    else:
        assert child.stdin is not None
        child.stdin.write("crash\n")
        child.stdin.flush()
    got = b""
    while len(got) < len(STOP) and time.monotonic() - killed < 0.5:
        got += _read_for(line, 0.02)
    after = time.monotonic() - killed
    assert got == STOP, got
    assert after < 0.5
    assert _gone_within(guardian, 1.0), "the guardian outlived the session"
    if how == "crash":
        assert child.wait(5) == -signal.SIGSEGV
    return after


def test_kill_9_on_a_pty_sends_the_stop_within_half_a_second() -> None:
    with _pty() as (device, master), _driver(device) as (child, guardian):
        _kill_and_expect_stop(child, guardian, master)
        assert _read_for(master, 0.2) == b""  # once, then nothing


def test_an_interpreter_crash_sends_the_stop_within_half_a_second() -> None:
    with _pty() as (device, master), _driver(device) as (child, guardian):
        _kill_and_expect_stop(child, guardian, master, how="crash")


def test_kill_9_on_a_socket_sends_the_stop_within_half_a_second() -> None:
    with _tcp() as (url, accept), _driver(url) as (child, guardian):
        _kill_and_expect_stop(child, guardian, accept())


@pytest.mark.parametrize("line", ["pty", "socket"])
def test_a_clean_close_sends_nothing_and_leaves_no_guardian(line: str) -> None:
    opened = _pty() if line == "pty" else _tcp()
    with opened as (url, other), _driver(url) as (child, guardian):
        fd = other if isinstance(other, int) else other()
        assert child.stdin is not None
        assert child.stdout is not None
        child.stdin.write("release\n")
        child.stdin.flush()
        assert child.stdout.readline().strip() == "released"
        assert not _alive(guardian)
        child.kill()  # the driving process dies after its clean close: still nothing
        child.wait()
        assert _read_for(fd, 0.3) == b""


def test_the_in_process_fakes_have_no_line_to_guard() -> None:
    """fakerobot:// and fakecreate2:// run in the driving process: they die with
    it, so there is nothing left to stop (docs/sessions.md)."""
    fakes.register_url_handlers()
    for url in ("fakerobot://?seed=1", "fakecreate2://?seed=1"):
        port = open_serial_url(url, 115200)
        try:
            assert line_fd(port) is None
            assert start_guardian(port, STOP) is None
        finally:
            port.close()


def _ignored_signals(pid: int) -> int:
    """The mask of signals ``pid`` ignores (/proc/PID/status SigIgn)."""
    with open(f"/proc/{pid}/status", encoding="ascii") as status:
        for row in status:
            if row.startswith("SigIgn:"):
                return int(row.split()[1], 16)
    raise AssertionError(f"no SigIgn in /proc/{pid}/status")


def test_the_guardian_is_waiting_when_start_guardian_returns() -> None:
    """Armed means armed: once start_guardian returns, the guardian runs its own
    code (its terminal signals ignored, the pipe read), not an interpreter still
    starting. A guardian still starting would send a process killed at once its
    stop late: seen in CI (tests/session/test_cli.py's kill -9 loop) as a stale
    stop that ended the next session's turn on the same line."""
    with _pty() as (device, master):
        port = open_serial_url(device, 115200)
        try:
            guardian = start_guardian(port, STOP)
            assert guardian is not None
            mask = _ignored_signals(guardian.pid)
            for name in ("SIGINT", "SIGHUP", "SIGQUIT", "SIGTSTP"):
                assert mask & (1 << (getattr(signal, name) - 1)), f"{name} not yet ignored"
            guardian.release()
        finally:
            port.close()
        assert _read_for(master, 0.1) == b""


def test_a_guardian_that_cannot_start_is_refused_before_anything_moves(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """An interpreter that cannot start (here: no standard library under its
    PYTHONHOME) never says it is ready: start_guardian raises SafetyError,
    nothing sent on the line, no guardian left."""
    with _pty() as (device, master):
        port = open_serial_url(device, 115200)
        try:
            monkeypatch.setenv("PYTHONHOME", "/nonexistent-odohil-test")
            with pytest.raises(SafetyError, match=r"ended before it was ready.*nothing moved"):
                start_guardian(port, STOP)
        finally:
            port.close()
        assert _read_for(master, 0.1) == b""
