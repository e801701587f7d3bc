"""Start a fake robot on a pty (shared by ``odohil emulate`` and ``python -m fakes.nomad``)."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import TextIO

from fakes.launch import OnReady, run_announced
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

    def serve_nomad(path: Path, ready: OnReady) -> None:
        serve(NomadEngine(config), baud=baud, pacing=pacing, truth_path=path, on_ready=ready)

    run_announced(serve_nomad, truth_socket=truth_socket, tmp_prefix="odohil-fake-", out=out)
