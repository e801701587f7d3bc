"""The client of a fake robot's truth side channel, shared by every fake.

A fake serves its TRUE state on a UNIX-domain stream socket beside its pty
(fakes/nomad/server.py): the client writes one line and reads one JSON line
back. What that JSON line holds is the robot's own business: each fake passes
in how to parse it (fakes/nomad/truth.py, fakes/create2/truth.py).
"""

from __future__ import annotations

import socket
from collections.abc import Callable
from pathlib import Path
from types import TracebackType
from typing import Generic, Self, TypeVar

from odohil.errors import ConnectionFailedError, OdohilTimeoutError

SnapshotT = TypeVar("SnapshotT")


class TruthChannelClient(Generic[SnapshotT]):
    """Client of a fake robot's truth socket; a context manager.

    Args:
        path: the UNIX-domain socket path the fake printed.
        timeout_s: how long one request may take, s.
        parse: turns one reply line (no newline) into the robot's snapshot.
        robot: how error messages name the fake (``fake robot``, ``fake Create 2``).
    """

    def __init__(
        self,
        path: str | Path,
        timeout_s: float,
        *,
        parse: Callable[[str], SnapshotT],
        robot: str,
    ) -> None:
        self.path = str(path)
        self.timeout_s = timeout_s
        self._parse = parse
        self._robot = robot
        self._sock: socket.socket | None = None
        self._buf = b""

    def __enter__(self) -> Self:
        self.open()
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()

    def open(self) -> None:
        """Connect to the socket (ConnectionFailedError if nobody listens)."""
        sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        sock.settimeout(self.timeout_s)
        try:
            sock.connect(self.path)
        except OSError as exc:
            sock.close()
            raise ConnectionFailedError(
                f"no {self._robot} truth socket at {self.path}: {exc}"
            ) from exc
        self._sock = sock

    def close(self) -> None:
        """Disconnect."""
        if self._sock is not None:
            self._sock.close()
            self._sock = None

    def ask(self, line: bytes) -> SnapshotT:
        """Send one request line (ending in a newline); the snapshot it answers."""
        if self._sock is None:
            self.open()
        assert self._sock is not None
        try:
            self._sock.sendall(line)
            while b"\n" not in self._buf:
                chunk = self._sock.recv(65536)
                if not chunk:
                    raise ConnectionFailedError(f"the {self._robot} closed the truth socket")
                self._buf += chunk
        except TimeoutError as exc:
            raise OdohilTimeoutError(f"truth socket silent for {self.timeout_s} s") from exc
        reply, _, self._buf = self._buf.partition(b"\n")
        return self._parse(reply.decode())
