"""``odohil emulate``: serve a fake robot (the Nomad 150 or the Create 2) on a
pseudo-terminal.

Which fake, and its defaults (line rate, time scale), come from the robot
backend's facts (``RobotFacts.fake``, read through odohil/session/robots/registry.py);
the fake (fakes/nomad/, fakes/create2/) is imported only when the command
runs, through the emulator its backend names, so that no other ``odohil``
command loads it.
"""

from __future__ import annotations

import logging
from typing import Annotated

import typer

from odohil.cli.options import Parameters, option, parameters_option, usage_errors
from odohil.science.robot_description import DEFAULT_PROTOCOL
from odohil.session.addresses import check_socket_path
from odohil.session.robots.description import robot_protocol
from odohil.session.robots.registry import emulate_help, emulated_line, emulator

_FAULT_HELP = (
    "Inject a fault: NAME, NAME:CODE or NAME:CODE@N (only the N-th matching request); "
    "repeatable; NAME as listed in docs/fake-robot.md (a wrong one is refused with the list)."
)


_HELP = emulate_help()


@parameters_option
def emulate(
    robot: str = typer.Option(DEFAULT_PROTOCOL, "--robot", help=_HELP.robot),
    seed: Annotated[
        int | None, option("--seed", bound="seed", help="Seed of the odometry noise.")
    ] = None,
    time_scale: Annotated[
        float | None, option("--time-scale", bound="time_scale", help=_HELP.time_scale)
    ] = None,
    baud: Annotated[int | None, option("--baud", bound="baud", help=_HELP.baud)] = None,
    pacing: bool = typer.Option(
        True, "--pacing/--no-pacing", help="Carry bytes at the line rate in both directions."
    ),
    fault: Annotated[list[str] | None, typer.Option("--fault", help=_FAULT_HELP)] = None,
    truth_socket: str | None = typer.Option(
        None, "--truth-socket", help="UNIX socket path for the true pose (default: a temp path)."
    ),
    verbose: bool = typer.Option(False, "--verbose", help="Log protocol events to stderr."),
    *,
    params: Parameters,
) -> None:
    """Serve a fake robot on a pseudo-terminal until Ctrl-C: the one --robot
    names (its backend's fake, odohil/session/robots/registry.py ``fake_hooks``).

    Prints the device path (first line) and the truth socket path (second line).
    """
    from fakes.launch import EmulateOptions

    if truth_socket is not None:
        with usage_errors("--truth-socket"):
            check_socket_path(truth_socket)
    logging.basicConfig(level=logging.INFO if verbose else logging.WARNING)
    with usage_errors("--robot"):
        facts, hooks, serve = emulator(robot_protocol(robot))
    with usage_errors("--baud"):
        baud, time_scale = emulated_line(facts, hooks, baud, time_scale)
    paper = params.to_paper_units()
    options = EmulateOptions(
        seed=seed,
        paper=(paper["E_R"], paper["E_T"], paper["K_theta"], paper["K_rho"]),
        time_scale=time_scale,
        baud=baud,
        pacing=pacing,
        faults=tuple(fault or ()),
        truth_socket=truth_socket,
    )
    with usage_errors():
        serve(options)
