"""Serve one fake Create 2 on a pseudo-terminal, with its truth socket beside it.

The fake Nomad's pty server (fakes/nomad/server.py) carries any engine with
its interface; this one adds the test hook of the truth socket: a line
``event NAME`` injects a safety event before the snapshot is sent.
"""

from __future__ import annotations

import signal
import socket
from collections.abc import Callable
from pathlib import Path
from types import FrameType
from typing import Any, cast

from fakes.create2.engine import Create2Engine
from fakes.nomad.server import PtyServer
from odohil.errors import ParameterError


class Create2PtyServer(PtyServer):
    """A :class:`PtyServer` for a :class:`Create2Engine` (truth lines may carry events)."""

    def __init__(self, engine: Create2Engine, baud: int, pacing: bool, truth_path: Path) -> None:
        super().__init__(cast(Any, engine), baud, pacing, truth_path)
        self.create2 = engine

    def _serve_client(self, client: socket.socket) -> None:
        try:
            chunk = client.recv(4096)
        except OSError:
            chunk = b""
        if not chunk:
            client.close()
            del self._clients[client]
            return
        buf = self._clients[client] + chunk
        while b"\n" in buf:
            line, _, buf = buf.partition(b"\n")
            words = line.decode(errors="replace").split()
            if len(words) == 2 and words[0] == "event":
                try:
                    self.create2.event(words[1])
                except ParameterError as exc:
                    words = [str(exc)]
            reply = self.create2.truth().to_json() + "\n"
            try:
                client.sendall(reply.encode())
            except OSError:
                client.close()
                del self._clients[client]
                return
        self._clients[client] = buf


def serve(
    engine: Create2Engine,
    *,
    baud: int,
    pacing: bool,
    truth_path: Path,
    on_ready: Callable[[str, str], None],
) -> None:
    """Run a :class:`Create2PtyServer` until SIGINT or SIGTERM; ``on_ready(device, socket)``."""
    server = Create2PtyServer(engine, baud, pacing, truth_path)

    def _handler(signum: int, frame: FrameType | None) -> None:
        server.stop()

    previous = {sig: signal.signal(sig, _handler) for sig in (signal.SIGINT, signal.SIGTERM)}
    try:
        server.start()
        on_ready(server.device, str(truth_path))
        server.run()
    finally:
        server.close()
        for sig, old in previous.items():
            signal.signal(sig, old)
