"""Start a fake robot on a pty (shared by ``odohil emulate`` and ``python -m fakes.nomad``)."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import TextIO

from fakes.launch import EmulateOptions, OnReady, run_announced
from fakes.nomad.config import EmulatorConfig, build_config
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


def emulate(options: EmulateOptions) -> None:
    """``odohil emulate --robot nomad150`` (the hook in the backend's
    ``FakeFacts.emulator``): build the fake from ``options`` and serve it.
    OdohilError for a bad option (a fault string, a parameter)."""
    e_r, e_t, k_theta, k_rho = options.paper
    config = build_config(
        seed=options.seed,
        e_r_deg_per_m=e_r,
        e_t=e_t,
        k_theta_deg2_per_m=k_theta,
        k_rho_m=k_rho,
        time_scale=options.time_scale,
        faults=list(options.faults),
    )
    run_emulator(
        config, baud=options.baud, pacing=options.pacing, truth_socket=options.truth_socket
    )
