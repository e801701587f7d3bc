"""Start a fake Create 2 on a pty (``odohil emulate --robot create2`` and
``python -m fakes.create2``)."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import TextIO

from fakes.create2.config import Create2Config
from fakes.create2.engine import Create2Engine
from fakes.create2.server import serve
from fakes.launch import OnReady, run_announced


def run_emulator(
    config: Create2Config,
    *,
    pacing: bool,
    truth_socket: str | None,
    out: TextIO = sys.stdout,
) -> None:
    """Serve until SIGINT/SIGTERM, printing the pty device path and the truth
    socket path as the first two lines of ``out`` (as the fake Nomad does)."""

    def serve_create2(path: Path, ready: OnReady) -> None:
        serve(
            Create2Engine(config), baud=config.baud, pacing=pacing, truth_path=path, on_ready=ready
        )

    run_announced(serve_create2, truth_socket=truth_socket, tmp_prefix="odohil-create2-", out=out)
