"""``odohil`` as a real OS process, without paying its start-up each time.

Tests where the process is the point (kill -9 anywhere, a signal mid-motion,
the guardian's stop) need odohil in a process of its own: its own pid, its
own signal handlers, descriptors the kernel closes when it dies. They do not
need the interpreter's start and odohil's imports (about 2 CPU seconds per
command, scipy.stats most of it), which the console script pays on every run.

:func:`start` forks the command from a server process that imported odohil
once (multiprocessing's ``forkserver``: a fresh single-threaded interpreter
started from this one, not a fork of the test runner). The child sets
``sys.argv`` as the console script would and calls the console script's own
entry point, :func:`odohil.cli.app.main`; its stdout and stderr are pipes,
and its exit status is the command's (``sys.exit``'s code, or minus the
signal that killed it), as :class:`subprocess.Popen` reports it. What differs
from the console script: no ``exec`` and no imports in the child, stdin is
``/dev/null``, and its parent is the fork server rather than the test.

:func:`spawn` forks it the same way onto a pseudo-terminal (the interactive
wizard): the child starts a session of its own with the pty as its
controlling terminal and stdin, stdout and stderr, and the test drives it
with pexpect on the pty's master side, as ``pexpect.spawn`` drives a console
process.
"""

from __future__ import annotations

import fcntl
import importlib
import multiprocessing
import os
import signal
import struct
import subprocess
import sys
import termios
import threading
import time
from multiprocessing import reduction
from types import TracebackType
from typing import Self, TextIO

from pexpect import fdpexpect

PRELOAD = [
    "odohil.cli.app",
    "odohil.cli.run",
    "odohil.cli.resume",
    "odohil.session.results.outcome",
    "odohil.science.estimators",
    "scipy.special",
    "odohil.session.results.report.plots",
    "fakes",
    "fakes.nomad.__main__",
    "fakes.create2.__main__",
    "typer._adapters",
    "typer.rich_utils",
]
"""What the fork server imports once: the run and resume commands and the science
(scipy.special included: odohil imports it at the first probability it computes,
odohil/science/distributions.py), and the report's plots (matplotlib: 0.6 s of
CPU, which each forked ``odohil report`` paid before); typer's parameter
adapters (pydantic: 0.1 s of CPU, which every forked command paid when typer
converted its first option) and its rich help and error rendering (0.06 s)."""

_CONTEXT = multiprocessing.get_context("forkserver")
_CONTEXT.set_forkserver_preload(PRELOAD)


class _PassFd:
    """A descriptor handed to the child when the process object is pickled for
    the fork server (which passes it with the request, SCM_RIGHTS): the child
    gets its own copy, and no other copy stays behind in this process (as
    ``reduction.DupFd`` made outside pickling would, in its resource sharer)."""

    def __init__(self, fd: int) -> None:
        self.fd = fd

    def __reduce__(self) -> tuple[object, tuple[object]]:
        return (_received, (reduction.DupFd(self.fd),))


def _received(dup: reduction.DupFd) -> int:
    """In the child: the descriptor the fork server passed."""
    return int(dup.detach())


def _child(args: list[str], out: int, err: int, env: dict[str, str] | None) -> None:
    """In the forked process: the environment, stdout and stderr to the pipes, then
    the console script."""
    if env is not None:
        os.environ.clear()
        os.environ.update(env)
    for fd, write_end in ((1, out), (2, err)):
        os.dup2(write_end, fd)
        os.close(write_end)
    sys.argv = ["odohil", *args]
    from odohil.cli.app import main

    main()


class _Reader:
    """Reads a pipe to its end (every writer gone) in a thread, as Popen.communicate does."""

    def __init__(self, fd: int) -> None:
        self._fd = fd
        self._chunks: list[bytes] = []
        self._thread = threading.Thread(target=self._read, daemon=True)
        self._thread.start()

    def _read(self) -> None:
        try:
            while chunk := os.read(self._fd, 65536):
                self._chunks.append(chunk)
        finally:
            os.close(self._fd)

    def join(self, timeout: float | None) -> None:
        self._thread.join(timeout)
        if self._thread.is_alive():
            raise TimeoutError("a process still holds the pipe open")

    def text(self) -> str:
        return b"".join(self._chunks).decode("utf-8", errors="replace")


class Forked:
    """One forked ``odohil ARGS`` (the subset of :class:`subprocess.Popen` the tests use:
    its stdout and stderr are read to their end, which comes when every process
    holding them has gone, the guardian included).

    Args:
        args: the command line after ``odohil``.
        env: its environment (default: the fork server's, which is the test
            process's when the server started).
    """

    def __init__(self, args: list[str], env: dict[str, str] | None = None) -> None:
        out_r, out_w = os.pipe()
        err_r, err_w = os.pipe()
        try:
            self._process = _CONTEXT.Process(
                target=_child,
                args=(list(args), _PassFd(out_w), _PassFd(err_w), env),
            )
            self._process.start()
        finally:
            os.close(out_w)
            os.close(err_w)
        self._out = _Reader(out_r)
        self._err = _Reader(err_r)
        pid = self._process.pid
        assert pid is not None
        self.pid: int = pid
        self._closed_code: int | None = None

    @property
    def returncode(self) -> int | None:
        """The exit status (minus the signal number if a signal ended it), None while it runs."""
        return self.poll()

    def poll(self) -> int | None:
        """The exit status if it has ended, else None."""
        if self._closed_code is not None:
            return self._closed_code
        return self._process.exitcode

    def wait(self, timeout: float | None = None) -> int:
        """Wait for the end (TimeoutError after ``timeout`` s); its exit status."""
        if self._closed_code is not None:
            return self._closed_code
        self._process.join(timeout)
        code = self._process.exitcode
        if code is None:
            raise TimeoutError(f"odohil (pid {self.pid}) still runs after {timeout} s")
        return code

    def send_signal(self, signum: int) -> None:
        """Send ``signum`` to the process (nothing once it has ended)."""
        if self.poll() is None:
            os.kill(self.pid, signum)

    def kill(self) -> None:
        """SIGKILL."""
        self.send_signal(signal.SIGKILL)

    def communicate(self, timeout: float | None = None) -> tuple[str, str]:
        """Wait for the end and for stdout and stderr to close; what was written on them."""
        deadline = None if timeout is None else time.monotonic() + timeout
        self.wait(timeout)
        for reader in (self._out, self._err):
            reader.join(None if deadline is None else max(0.0, deadline - time.monotonic()))
        return self._out.text(), self._err.text()

    def close(self) -> None:
        """Kill it if it still runs."""
        if self._closed_code is not None:
            return
        if self._process.exitcode is None:
            self.kill()
        self._closed_code = self.wait(30)
        self._process.close()

    def __enter__(self) -> Self:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()


def _pty_child(args: list[str], slave: int, env: dict[str, str] | None) -> None:
    """In the forked process: a session of its own whose controlling terminal is
    the pseudo-terminal ``slave``, stdin, stdout and stderr on it (text streams
    rebuilt as the interpreter builds them on a terminal: line-buffered), then
    the console script."""
    os.setsid()
    fcntl.ioctl(slave, termios.TIOCSCTTY, 0)
    if env is not None:
        os.environ.clear()
        os.environ.update(env)
    for fd in (0, 1, 2):  # (multiprocessing's /dev/null on 0 is replaced)
        os.dup2(slave, fd)
    if slave > 2:
        os.close(slave)
    sys.stdin = open(0, encoding="utf-8", closefd=False)  # noqa: SIM115
    sys.stdout = open(1, "w", encoding="utf-8", closefd=False)  # noqa: SIM115
    sys.stderr = open(  # noqa: SIM115
        2, "w", encoding="utf-8", errors="backslashreplace", closefd=False, buffering=1
    )
    sys.argv = ["odohil", *args]
    from odohil.cli.app import main

    main()


class PtyForked(fdpexpect.fdspawn):
    """``odohil ARGS`` forked from the server (as :class:`Forked`) on a
    pseudo-terminal: its controlling terminal, stdin, stdout and stderr, as
    ``pexpect.spawn`` gives a console process; Ctrl-C typed on it
    (:meth:`sendintr`) is the terminal's SIGINT to the process. The subset of
    ``pexpect.spawn`` the tests use: expect, sendline, sendintr, kill, wait,
    close, exitstatus (None when a signal ended it: then signalstatus).

    Args:
        args: the command line after ``odohil``.
        env: its environment.
        dimensions: the terminal's (rows, columns).
        timeout: expect's timeout, s.
        logfile: where what is read and sent is also written (None: nowhere).
    """

    def __init__(
        self,
        args: list[str],
        env: dict[str, str] | None,
        dimensions: tuple[int, int],
        timeout: float,
        logfile: TextIO | None = None,
    ) -> None:
        master, slave = os.openpty()
        try:
            fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", *dimensions, 0, 0))
            self._process = _CONTEXT.Process(
                target=_pty_child, args=(list(args), _PassFd(slave), env)
            )
            self._process.start()
        finally:
            os.close(slave)
        super().__init__(master, timeout=timeout, encoding="utf-8", logfile=logfile)
        pid = self._process.pid
        assert pid is not None
        self.pid: int = pid
        self.exitstatus: int | None = None
        self.signalstatus: int | None = None

    def sendintr(self) -> None:
        """Type Ctrl-C (the terminal's interrupt character)."""
        self.send("\x03")

    def kill(self, sig: int) -> None:
        """Send ``sig`` to the process (nothing once it has ended)."""
        if self._process.exitcode is None:
            os.kill(self.pid, sig)

    def wait(self, timeout: float | None = 30.0) -> int | None:
        """Wait for the end (TimeoutError after ``timeout`` s); its exit status."""
        self._process.join(timeout)
        code = self._process.exitcode
        if code is None:
            raise TimeoutError(f"odohil (pid {self.pid}) still runs after {timeout} s")
        self.exitstatus, self.signalstatus = (code, None) if code >= 0 else (None, -code)
        return self.exitstatus

    def close(self, force: bool = True) -> None:
        """Close the terminal (a process still on it gets its hang-up), wait for
        the end, and kill it if it has not ended within 5 s."""
        super().close()
        self._process.join(5.0)
        if self._process.exitcode is None and force:
            os.kill(self.pid, signal.SIGKILL)
        self.wait()


def spawn(
    args: list[str],
    env: dict[str, str] | None = None,
    dimensions: tuple[int, int] = (24, 80),
    timeout: float = 30.0,
    logfile: TextIO | None = None,
) -> PtyForked:
    """``odohil ARGS`` forked from the server on a pseudo-terminal (:class:`PtyForked`)."""
    return PtyForked(args, env, dimensions, timeout, logfile)


def start(args: list[str], env: dict[str, str] | None = None) -> Forked:
    """``odohil ARGS`` forked from the server (module docstring)."""
    return Forked(args, env)


def run(
    args: list[str], timeout_s: float = 120.0, env: dict[str, str] | None = None
) -> tuple[int, str, str]:
    """``odohil ARGS`` to its end: exit status, stdout, stderr."""
    with start(args, env) as process:
        deadline = time.monotonic() + timeout_s
        out, err = process.communicate(max(0.0, deadline - time.monotonic()))
        return process.wait(), out, err


def completed(
    command: list[str], timeout: float = 120.0, env: dict[str, str] | None = None
) -> subprocess.CompletedProcess[str]:
    """``subprocess.run(command, capture_output=True, text=True, timeout=..., env=...)``
    for ``command = [the odohil console script, *ARGS]``, forked (module docstring)."""
    code, out, err = run(command[1:], timeout, env)
    return subprocess.CompletedProcess(command, code, out, err)


FAKE_MODULES = ("fakes.nomad", "fakes.create2")
"""The fakes :func:`start_fake` forks (``python -m MODULE``)."""


def _fake_child(module: str, args: list[str], out: int) -> None:
    """In the forked process: stdout to the pipe, then ``python -m MODULE ARGS``
    (the module's ``__main__.main``, which the server imported)."""
    os.dup2(out, 1)
    os.close(out)
    sys.argv = [f"python -m {module}", *args]
    importlib.import_module(f"{module}.__main__").main(list(args))


class ForkedFake:
    """``python -m MODULE ARGS`` (a fake robot) forked from the server: what
    fakes/nomad/process.py's ``Started`` asks for, stdout a pipe it reads its
    two paths from. The fake's own process as an exec'd one would be (its pty,
    its truth socket, its signal handlers), without the interpreter's start and
    numpy's import (about 0.25 CPU s each, a hundred fakes a run)."""

    def __init__(self, module: str, args: list[str]) -> None:
        out_r, out_w = os.pipe()
        try:
            self._process = _CONTEXT.Process(
                target=_fake_child, args=(module, list(args), _PassFd(out_w))
            )
            self._process.start()
        finally:
            os.close(out_w)
        self._out: int | None = out_r
        pid = self._process.pid
        assert pid is not None
        self.pid: int = pid

    @property
    def stdout_fd(self) -> int:
        assert self._out is not None
        return self._out

    def poll(self) -> int | None:
        return self._process.exitcode

    def terminate(self) -> None:
        if self.poll() is None:
            os.kill(self.pid, signal.SIGTERM)

    def kill(self) -> None:
        if self.poll() is None:
            os.kill(self.pid, signal.SIGKILL)

    def wait(self, timeout: float | None = None) -> int:
        self._process.join(timeout)
        code = self._process.exitcode
        if code is None:
            raise subprocess.TimeoutExpired(["python", "-m", "fake"], timeout or 0.0)
        return code

    def close(self) -> None:
        if self._out is not None:
            os.close(self._out)
            self._out = None


def start_fake(command: list[str]) -> ForkedFake | None:
    """``[python, "-m", MODULE, *ARGS]`` of a fake in :data:`FAKE_MODULES`,
    forked from the server; None for any other command."""
    if len(command) >= 3 and command[1] == "-m" and command[2] in FAKE_MODULES:
        return ForkedFake(command[2], command[3:])
    return None
