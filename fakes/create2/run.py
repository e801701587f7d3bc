"""Start a fake Create 2 on a pty (``odohil emulate --robot create2`` and
``python -m fakes.create2``)."""

from __future__ import annotations

import shutil
import sys
import tempfile
from pathlib import Path
from typing import TextIO

from fakes.create2.config import Create2Config
from fakes.create2.engine import Create2Engine
from fakes.create2.server import serve


def run_emulator(
    config: Create2Config,
    *,
    pacing: bool,
    truth_socket: str | None,
    out: TextIO = sys.stdout,
) -> None:
    """Serve until SIGINT/SIGTERM, printing the pty device path and the truth
    socket path as the first two lines of ``out`` (as the fake Nomad does)."""
    tmpdir: str | None = None
    if truth_socket is None:
        tmpdir = tempfile.mkdtemp(prefix="odohil-create2-")
        path = Path(tmpdir) / "truth.sock"
    else:
        path = Path(truth_socket)

    def ready(device: str, socket_path: str) -> None:
        out.write(f"{device}\n{socket_path}\n")
        out.flush()

    try:
        serve(
            Create2Engine(config),
            baud=config.baud,
            pacing=pacing,
            truth_path=path,
            on_ready=ready,
        )
    finally:
        if tmpdir is not None:
            shutil.rmtree(tmpdir, ignore_errors=True)
