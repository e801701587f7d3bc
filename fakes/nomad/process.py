"""Run the fake robot as a subprocess on a pty: for tests and ``odohil demo``."""

from __future__ import annotations

import os
import select
import subprocess
import sys
import time
from collections.abc import Sequence
from types import TracebackType

from fakes.nomad.truth import TruthClient, TruthSnapshot
from odohil.errors import ConnectionFailedError


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
        self.startup_timeout_s = startup_timeout_s
        self.stop_timeout_s = stop_timeout_s
        self.device = ""
        self.truth_socket = ""
        self._proc: subprocess.Popen[bytes] | None = None

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
        proc = subprocess.Popen(self.command, stdout=subprocess.PIPE)
        self._proc = proc
        assert proc.stdout is not None
        fd = proc.stdout.fileno()
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
            if proc is not None and proc.stdout is not None:
                proc.stdout.close()
            return
        proc.terminate()
        try:
            proc.wait(self.stop_timeout_s)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
        if proc.stdout is not None:
            proc.stdout.close()
