"""``odohil emulate``: serve a fake robot (the Nomad 150 or the Create 2) on a
pseudo-terminal.

Which fake, and its defaults (line rate, time scale), come from the robot
backend's facts (``RobotFacts.fake``, read through odohil/session/robots.py);
the fake (fakes/nomad/, fakes/create2/) is imported only when the command
runs, through the emulator its backend names, so that no other ``odohil``
command loads it.
"""

from __future__ import annotations

import logging
import os
from collections.abc import Callable
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
from odohil.errors import InitError, OdohilError
from odohil.science.robot_description import DEFAULT_PROTOCOL
from odohil.science.robot_facts import RobotFacts
from odohil.session.robots import backend_names, fake_hooks, robot_facts

_FAULT_HELP = (
    "Inject a fault: NAME, NAME:CODE or NAME:CODE@N (only the N-th matching request); "
    "repeatable; NAME as listed in docs/fake-robot.md (a wrong one is refused with the list)."
)


def _with_fakes() -> list[RobotFacts]:
    """The facts of every registered backend that declares a fake to emulate."""
    found = []
    for name in backend_names():
        try:
            facts = robot_facts(name)
        except OdohilError:
            continue
        if facts.fake is not None and facts.fake.emulator:
            found.append(facts)
    return found


def _robot_help() -> str:
    names = ", ".join(f"{f.name} (the {f.label})" for f in _with_fakes()) or "none installed"
    return (
        f"Which fake robot: {names}, or a robot description file whose "
        "\\[robot] protocol is one of them."
    )


def _default_help(what: str, value: Callable[[RobotFacts], float]) -> str:
    per_robot = ", ".join(f"{f.name} {value(f):g}" for f in _with_fakes())
    return f"default: the robot's own {what} ({per_robot})"


def emulate(
    robot: str = typer.Option(DEFAULT_PROTOCOL, "--robot", help=_robot_help()),
    seed: int | None = typer.Option(
        None, "--seed", callback=bounded("seed"), help="Seed of the odometry noise."
    ),
    e_r: ERDegPerM = E_R_DEFAULT,
    e_t: ETOption = E_T_DEFAULT,
    k_theta: KThetaDeg2PerM = K_THETA_DEFAULT,
    k_rho: KRhoM = K_RHO_DEFAULT,
    time_scale: float | None = typer.Option(
        None,
        "--time-scale",
        callback=bounded("time_scale"),
        help="Simulated seconds per wall second (motion, zr, timestamp); "
        + _default_help("time scale", lambda f: f.fake.emulate_time_scale if f.fake else 1.0)
        + ".",
    ),
    baud: int | None = typer.Option(
        None,
        "--baud",
        callback=bounded("baud"),
        help="Line rate (pacing and the pty speed); "
        + _default_help("line rate, its backend's default baud", lambda f: f.default_baud)
        + ".",
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
    """Serve a fake robot on a pseudo-terminal until Ctrl-C: the one --robot
    names (its backend's fake, odohil/session/robots.py ``fake_hooks``).

    Prints the device path (first line) and the truth socket path (second line).
    """
    from fakes.launch import EmulateOptions

    if truth_socket is not None:
        _check_socket_path(truth_socket)
    logging.basicConfig(level=logging.INFO if verbose else logging.WARNING)
    protocol = robot_protocol(robot)
    try:
        facts = robot_facts(protocol)
        hooks = fake_hooks(protocol)
        if hooks is None or not hooks.emulator:
            raise InitError(f"the {protocol} backend declares no fake robot to emulate")
        serve = hooks.emulator_function()
    except OdohilError as exc:
        raise typer.BadParameter(str(exc), param_hint="--robot") from exc
    if baud is not None and not facts.speaks(baud):
        raise typer.BadParameter(
            f"the {facts.label} speaks {facts.rates_text()} baud, got {baud}", param_hint="--baud"
        )
    options = EmulateOptions(
        seed=seed,
        paper=(e_r, e_t, k_theta, k_rho),
        time_scale=hooks.emulate_time_scale if time_scale is None else time_scale,
        baud=facts.default_baud if baud is None else baud,
        pacing=pacing,
        faults=tuple(fault or ()),
        truth_socket=truth_socket,
    )
    try:
        serve(options)
    except OdohilError as exc:
        raise typer.BadParameter(str(exc)) from exc


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
