"""Start a fake Create 2 on a pty (``odohil emulate --robot create2`` and
``python -m fakes.create2``)."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import TextIO

from fakes.create2.config import HOST_BOUND_S, Create2Config, build_config
from fakes.create2.engine import Create2Engine
from fakes.create2.server import serve
from fakes.launch import EmulateOptions, OnReady, run_announced
from odohil.science.parameters import ErrorParameters


def run_emulator(
    config: Create2Config,
    *,
    pacing: bool,
    truth_socket: str | None,
    host_bound_s: float | None = HOST_BOUND_S,
    out: TextIO = sys.stdout,
) -> None:
    """Serve until SIGINT/SIGTERM, printing the pty device path and the truth
    socket path as the first two lines of ``out`` (as the fake Nomad does).
    ``host_bound_s``: how far the motion runs past what the host has read,
    wall s (None: unbounded; :data:`~fakes.create2.config.HOST_BOUND_S`)."""

    def serve_create2(path: Path, ready: OnReady) -> None:
        engine = Create2Engine(config, host_bound_s=host_bound_s)
        serve(engine, baud=config.baud, pacing=pacing, truth_path=path, on_ready=ready)

    run_announced(serve_create2, truth_socket=truth_socket, tmp_prefix="odohil-create2-", out=out)


def emulate(options: EmulateOptions) -> None:
    """``odohil emulate --robot create2`` (the hook in the backend's
    ``FakeFacts.emulator``): build the fake Create 2 from ``options`` and
    serve it. OdohilError for a bad option (a fault string, a parameter)."""
    config = build_config(
        seed=options.seed,
        params=ErrorParameters.from_paper_units(*options.paper),
        time_scale=options.time_scale,
        baud=options.baud,
        faults=list(options.faults),
    )
    run_emulator(config, pacing=options.pacing, truth_socket=options.truth_socket)
