"""Start a fake robot on a pty (shared by ``odohil emulate`` and ``python -m fakes.nomad``)."""

from __future__ import annotations

import shutil
import sys
import tempfile
from pathlib import Path
from typing import TextIO

from fakes.nomad.config import EmulatorConfig
from fakes.nomad.engine import NomadEngine
from fakes.nomad.server import serve


def run_emulator(
    config: EmulatorConfig,
    *,
    baud: int,
    pacing: bool,
    truth_socket: str | None,
    out: TextIO = sys.stdout,
) -> None:
    """Serve until SIGINT/SIGTERM.

    Prints the pty device path as the first line of ``out`` and the truth
    socket path as the second, then flushes. Without ``truth_socket`` the
    socket goes into a fresh temporary directory, removed at exit.
    """
    tmpdir: str | None = None
    if truth_socket is None:
        tmpdir = tempfile.mkdtemp(prefix="odohil-fake-")
        path = Path(tmpdir) / "truth.sock"
    else:
        path = Path(truth_socket)

    def ready(device: str, socket_path: str) -> None:
        out.write(f"{device}\n{socket_path}\n")
        out.flush()

    try:
        serve(NomadEngine(config), baud=baud, pacing=pacing, truth_path=path, on_ready=ready)
    finally:
        if tmpdir is not None:
            shutil.rmtree(tmpdir, ignore_errors=True)
