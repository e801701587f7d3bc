"""``odohil emulate``: serve a fake robot (the Nomad 150 or the Create 2) on a
pseudo-terminal.

The fake (fakes/nomad/, fakes/create2/) is imported only when the command
runs, so that no other ``odohil`` command loads it.
"""

from __future__ import annotations

import logging
import os
from pathlib import Path
from typing import Annotated

import typer

from odohil.cli.options import (
    E_R_DEFAULT,
    E_T_DEFAULT,
    K_RHO_DEFAULT,
    K_THETA_DEFAULT,
    ERDegPerM,
    ETOption,
    KRhoM,
    KThetaDeg2PerM,
    bounded,
)
from odohil.cli.robot_option import robot_protocol
from odohil.errors import OdohilError
from odohil.session.robots import find_backend

_FAULT_HELP = (
    "Inject a fault: NAME, NAME:CODE or NAME:CODE@N (only the N-th matching request); "
    "repeatable; NAME as listed in docs/fake-robot.md (a wrong one is refused with the list)."
)


def emulate(
    robot: str = typer.Option(
        "nomad150",
        "--robot",
        help="Which fake: nomad150 or create2 (docs/create2.md), "
        "or a robot description file whose \\[robot] protocol is one of them.",
    ),
    seed: int | None = typer.Option(
        None, "--seed", callback=bounded("seed"), help="Seed of the odometry noise."
    ),
    e_r: ERDegPerM = E_R_DEFAULT,
    e_t: ETOption = E_T_DEFAULT,
    k_theta: KThetaDeg2PerM = K_THETA_DEFAULT,
    k_rho: KRhoM = K_RHO_DEFAULT,
    time_scale: float = typer.Option(
        1.0,
        "--time-scale",
        callback=bounded("time_scale"),
        help="Simulated seconds per wall second (motion, zr, timestamp).",
    ),
    baud: int | None = typer.Option(
        None,
        "--baud",
        callback=bounded("baud"),
        help="Line rate (pacing and the pty speed); default: the robot's own "
        "(its backend's default baud).",
    ),
    pacing: bool = typer.Option(
        True, "--pacing/--no-pacing", help="Carry bytes at the line rate in both directions."
    ),
    fault: Annotated[list[str] | None, typer.Option("--fault", help=_FAULT_HELP)] = None,
    truth_socket: str | None = typer.Option(
        None, "--truth-socket", help="UNIX socket path for the true pose (default: a temp path)."
    ),
    verbose: bool = typer.Option(False, "--verbose", help="Log protocol events to stderr."),
) -> None:
    """Serve a fake robot on a pseudo-terminal until Ctrl-C: the Nomad 150, or
    with --robot create2 the Create 2.

    Prints the device path (first line) and the truth socket path (second line).
    """
    from fakes.nomad.config import build_config
    from fakes.nomad.run import run_emulator

    if truth_socket is not None:
        _check_socket_path(truth_socket)
    logging.basicConfig(level=logging.INFO if verbose else logging.WARNING)
    robot = robot_protocol(robot)
    if baud is None:
        baud = find_backend(robot).default_baud
    if robot == "create2":
        _emulate_create2(
            seed, (e_r, e_t, k_theta, k_rho), time_scale, baud, pacing, fault, truth_socket
        )
        return
    if robot != "nomad150":
        raise typer.BadParameter(f"one of nomad150, create2; got {robot!r}", param_hint="--robot")
    try:
        config = build_config(
            seed=seed,
            e_r_deg_per_m=e_r,
            e_t=e_t,
            k_theta_deg2_per_m=k_theta,
            k_rho_m=k_rho,
            time_scale=time_scale,
            faults=fault or [],
        )
    except OdohilError as exc:
        raise typer.BadParameter(str(exc)) from exc
    run_emulator(config, baud=baud, pacing=pacing, truth_socket=truth_socket)


def _emulate_create2(
    seed: int | None,
    paper: tuple[float, float, float, float],
    time_scale: float,
    baud: int,
    pacing: bool,
    fault: list[str] | None,
    truth_socket: str | None,
) -> None:
    """``--robot create2``: the fake Create 2 (fakes/create2/), same two lines
    and truth socket."""
    from fakes.create2.config import build_config as build_create2
    from fakes.create2.run import run_emulator as run_create2
    from odohil.science.parameters import ErrorParameters

    try:
        config = build_create2(
            seed=seed,
            params=ErrorParameters.from_paper_units(*paper),
            time_scale=time_scale,
            baud=baud,
            faults=fault or [],
        )
    except OdohilError as exc:
        raise typer.BadParameter(str(exc)) from exc
    run_create2(config, pacing=pacing, truth_socket=truth_socket)


SOCKET_PATH_MAX = 107
"""Longest UNIX socket path, bytes (sun_path holds 108 with the final NUL)."""


def _check_socket_path(path: str) -> None:
    """Usage error (exit 2) unless a UNIX socket can be made at ``path``."""
    size = len(os.fsencode(path))
    if not path or size > SOCKET_PATH_MAX:
        raise typer.BadParameter(
            f"a socket path must be 1 to {SOCKET_PATH_MAX} bytes long, got {size}",
            param_hint="--truth-socket",
        )
    folder = Path(path).parent
    if not folder.is_dir():
        raise typer.BadParameter(
            f"folder {str(folder)!r} does not exist", param_hint="--truth-socket"
        )


def register(app: typer.Typer) -> None:
    """Add ``emulate`` to the ``odohil`` app."""
    app.command("emulate")(emulate)
