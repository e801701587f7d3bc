"""Serve one fake Create 2 on a pseudo-terminal, with its truth socket beside it.

The fake Nomad's pty server (fakes/nomad/server.py) carries any engine with
its interface; this one adds the test hook of the truth socket: a line
``event NAME`` injects a safety event before the snapshot is sent.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable
from pathlib import Path
from typing import Any, cast

from fakes.create2.engine import Create2Engine
from fakes.nomad.server import PtyServer, serve_until_signalled
from odohil.errors import ParameterError


class Create2PtyServer(PtyServer):
    """A :class:`PtyServer` for a :class:`Create2Engine` (truth lines may carry events)."""

    def __init__(self, engine: Create2Engine, baud: int, pacing: bool, truth_path: Path) -> None:
        super().__init__(cast(Any, engine), baud, pacing, truth_path)
        self.create2 = engine

    def _truth_reply(self, line: str) -> str:
        words = line.split()
        if len(words) == 2 and words[0] == "event":
            # an unknown event injects nothing; the reply is the state as it is
            with contextlib.suppress(ParameterError):
                self.create2.event(words[1])
        return self.create2.truth().to_json()


def serve(
    engine: Create2Engine,
    *,
    baud: int,
    pacing: bool,
    truth_path: Path,
    on_ready: Callable[[str, str], None],
) -> None:
    """Run a :class:`Create2PtyServer` until SIGINT or SIGTERM; ``on_ready(device, socket)``."""
    serve_until_signalled(Create2PtyServer(engine, baud, pacing, truth_path), on_ready)
