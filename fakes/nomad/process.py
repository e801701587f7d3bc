"""Run the fake robot as a subprocess on a pty: for tests and ``odohil demo``."""

from __future__ import annotations

import os
import select
import subprocess
import sys
import time
from collections.abc import Callable, Sequence
from types import TracebackType
from typing import Protocol

from fakes.nomad.truth import TruthClient, TruthSnapshot
from odohil.errors import ConnectionFailedError


class Started(Protocol):
    """A started fake's process, as :class:`EmulatorProcess` uses it (the
    subset of :class:`subprocess.Popen` it needs, stdout a pipe)."""

    @property
    def stdout_fd(self) -> int:
        """The read end of its stdout."""
        ...

    def poll(self) -> int | None:
        """The exit status (minus the signal number) once it has ended, else None."""
        ...

    def terminate(self) -> None:
        """SIGTERM."""
        ...

    def kill(self) -> None:
        """SIGKILL."""
        ...

    def wait(self, timeout: float | None = None) -> int:
        """Its exit status; :class:`subprocess.TimeoutExpired` after ``timeout`` s."""
        ...

    def close(self) -> None:
        """Close the read end of its stdout."""
        ...


class _Popen:
    """:class:`Started` by :class:`subprocess.Popen` (exec of the command)."""

    def __init__(self, command: list[str]) -> None:
        self._popen = subprocess.Popen(command, stdout=subprocess.PIPE)
        assert self._popen.stdout is not None
        self._stdout = self._popen.stdout

    @property
    def stdout_fd(self) -> int:
        return self._stdout.fileno()

    def poll(self) -> int | None:
        return self._popen.poll()

    def terminate(self) -> None:
        self._popen.terminate()

    def kill(self) -> None:
        self._popen.kill()

    def wait(self, timeout: float | None = None) -> int:
        return self._popen.wait(timeout)

    def close(self) -> None:
        self._stdout.close()


Launcher = Callable[[list[str]], Started | None]
"""Starts a command (``[python, "-m", module, *args]``) as a fake's process,
or returns None to leave it to exec."""


def _exec(command: list[str]) -> Started | None:
    return None


_launcher: Launcher = _exec


def set_launcher(launcher: Launcher | None) -> None:
    """How ``python -m fakes...`` commands are started from now on (None: exec,
    the default). The test suite forks them from a server that imported the
    fakes once (tests/forked.py), saving the interpreter's start and numpy's
    import for each of its hundred fakes; ``odohil emulate`` commands
    (``use_cli``) are always exec'd."""
    global _launcher
    _launcher = _exec if launcher is None else launcher


class EmulatorProcess:
    """``python -m fakes.nomad ARGS`` (or ``odohil emulate ARGS``) as a context manager.

    On entry it starts the process and reads the pty device path and the truth
    socket path from its first two stdout lines; on exit it sends SIGTERM and
    waits (SIGKILL after ``stop_timeout_s``).

    Args:
        args: extra command-line options (``--seed``, ``--fault``...).
        use_cli: start ``odohil emulate`` instead of ``python -m fakes.nomad``.
        startup_timeout_s: how long to wait for the two paths, s.
        stop_timeout_s: how long to wait for a clean exit, s.
    """

    def __init__(
        self,
        args: Sequence[str] = (),
        *,
        use_cli: bool = False,
        startup_timeout_s: float = 20.0,
        stop_timeout_s: float = 5.0,
    ) -> None:
        prefix = (
            [sys.executable, "-m", "odohil", "emulate"]
            if use_cli
            else [sys.executable, "-m", "fakes.nomad"]
        )
        self.command = [*prefix, *args]
        self.use_cli = use_cli
        self.startup_timeout_s = startup_timeout_s
        self.stop_timeout_s = stop_timeout_s
        self.device = ""
        self.truth_socket = ""
        self._proc: Started | None = None

    def __enter__(self) -> EmulatorProcess:
        self.start()
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.stop()

    def start(self) -> None:
        """Start the process and wait for its two paths."""
        proc = None if self.use_cli else _launcher(self.command)
        if proc is None:
            proc = _Popen(self.command)
        self._proc = proc
        fd = proc.stdout_fd
        received = b""
        deadline = time.monotonic() + self.startup_timeout_s
        while received.count(b"\n") < 2:
            left = deadline - time.monotonic()
            ready, _, _ = select.select([fd], [], [], max(0.0, left))
            if not ready:
                self.stop()
                raise ConnectionFailedError(f"fake robot did not start: {self.command}")
            chunk = os.read(fd, 4096)
            if not chunk:
                self.stop()
                raise ConnectionFailedError(f"fake robot exited at start: {self.command}")
            received += chunk
        lines = [line.strip() for line in received.decode().splitlines()[:2]]
        self.device, self.truth_socket = lines

    @property
    def returncode(self) -> int | None:
        """The exit status once stopped (None while running)."""
        return None if self._proc is None else self._proc.poll()

    def truth(self) -> TruthSnapshot:
        """One snapshot from the truth socket."""
        with TruthClient(self.truth_socket) as client:
            return client.snapshot()

    def stop(self) -> None:
        """SIGTERM, wait, SIGKILL if needed."""
        proc = self._proc
        if proc is None or proc.poll() is not None:
            if proc is not None:
                proc.close()
            return
        proc.terminate()
        try:
            proc.wait(self.stop_timeout_s)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
        proc.close()
