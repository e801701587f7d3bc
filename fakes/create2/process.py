"""Run the fake Create 2 as a subprocess on a pty: for tests, benchmarks and the demo."""

from __future__ import annotations

import sys
from collections.abc import Sequence
from types import TracebackType

from fakes.create2.truth import Create2Truth, Create2TruthClient
from fakes.nomad.process import EmulatorProcess


class Create2Process:
    """``python -m fakes.create2 ARGS`` (or ``odohil emulate --robot create2
    ARGS``) as a context manager: on entry the pty device and truth socket
    paths are read from its first two lines; on exit it is stopped.
    """

    def __init__(
        self,
        args: Sequence[str] = (),
        *,
        use_cli: bool = False,
        startup_timeout_s: float = 20.0,
    ) -> None:
        self._process = EmulatorProcess(use_cli=use_cli, startup_timeout_s=startup_timeout_s)
        prefix = (
            [sys.executable, "-m", "odohil", "emulate", "--robot", "create2"]
            if use_cli
            else [sys.executable, "-m", "fakes.create2"]
        )
        self._process.command = [*prefix, *args]

    def __enter__(self) -> Create2Process:
        self._process.start()
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self._process.stop()

    @property
    def device(self) -> str:
        """The pty the robot's serial port is on."""
        return self._process.device

    @property
    def truth_socket(self) -> str:
        """The truth socket's path."""
        return self._process.truth_socket

    @property
    def returncode(self) -> int | None:
        """Exit status once stopped."""
        return self._process.returncode

    def truth(self) -> Create2Truth:
        """One snapshot of the true state."""
        with Create2TruthClient(self.truth_socket) as client:
            return client.snapshot()

    def event(self, name: str) -> Create2Truth:
        """Inject a safety event (test hook); the state after it."""
        with Create2TruthClient(self.truth_socket) as client:
            return client.event(name)

    def stop(self) -> None:
        """Stop the process."""
        self._process.stop()
