"""``odohil demo``: a whole calibration against the fake robot, unattended.

Starts the fake Nomad 150 (``python -m fakes.nomad``) on a pseudo-terminal with
known, exaggerated error parameters (:data:`DEMO_TRUTH`), runs the session
engine through the real driver with the fake's ground truth as measurement
source (1 mm tape noise), and prints the estimates beside the true values.
"""

from __future__ import annotations

import tempfile
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.console import Console

from odohil import units
from odohil.cli.line import resolve_line
from odohil.cli.options import UNITS_DEFAULT, UnitsOption, bounded, unit_system
from odohil.cli.render import parameters_line
from odohil.cli.robot_option import robot_protocol
from odohil.cli.run import (
    Outcome,
    connect,
    execute,
    finish,
    session_exit_codes,
    session_input,
)
from odohil.science.parameters import SI_UNITS, ErrorParameters
from odohil.science.robot_description import RobotDescription
from odohil.session.engine import start_session
from odohil.session.journal import Journal
from odohil.session.plan import parse_plan
from odohil.session.pose_kinds import SnapshotTruth
from odohil.session.robot import Robot
from odohil.session.robots import parse_description as parse_robot_description
from odohil.session.robots import robot_facts
from odohil.session.sources import FakeTruthSource, TapeSource
from odohil.session.state import SessionState

DEMO_TRUTH = ErrorParameters.from_paper_units(-1.0, -0.05, 0.3, 9e-4)
"""The fake robot's true parameters: the Nomad 150's (-0.202 deg/m, -0.02,
0.012 deg^2/m, 3.6e-5 m) scaled by about 5, 2.5, 25 and 25, so that the
odometry error of a 4 m trial stands well clear of 1 mm tape noise."""
DEMO_PLAN = "k=1,l=2,n=24;k=0.5,l=2,n=24"
"""Closed 4 m runs (E_R, K_theta, K_rho) and one-way 2 m runs (E_T)."""
DEMO_TIME_SCALE = 20000.0
"""Simulated seconds per wall second in the fake robot."""
DEMO_ROBOT_TOML = """\
[screws]
A = [0.20, 0.0]
B = [-0.10, 0.173]
C = [-0.10, -0.173]
[measurement]
sigma_m = 0.001
cross = [["A", "B"], ["B", "C"]]
"""


def demo(
    seed: Annotated[
        int,
        typer.Option("--seed", callback=bounded("seed"), help="Seed of the fake robot and tape."),
    ] = 1,
    json_out: Annotated[
        bool, typer.Option("--json", help="Print the estimate and the truth as JSON.")
    ] = False,
    session: Annotated[
        Path | None,
        typer.Option("--session", help="Keep the session folder here (default: a temp folder)."),
    ] = None,
    units_choice: UnitsOption = UNITS_DEFAULT,
    robot_name: Annotated[
        str,
        typer.Option(
            "--robot",
            help="Which fake robot: nomad150 or create2, or a robot description file whose "
            "\\[robot] protocol is one of them (docs/create2.md).",
        ),
    ] = "nomad150",
) -> None:
    """Calibrate the fake robot unattended and compare with its true parameters.

    The simulated operator measures with a 1 mm tape; when its distances fit no
    rigid motion (or one looks like a slip) it measures again, as a person
    would, and the demo says so.
    """
    system = unit_system(units_choice)
    robot_name = robot_protocol(robot_name)
    if robot_name == "create2":
        _demo_create2(seed, json_out, session, system)
        return
    if robot_name != "nomad150":
        raise typer.BadParameter(
            f"one of nomad150, create2; got {robot_name!r}", param_hint="--robot"
        )
    console = Console(stderr=True)
    truth = DEMO_TRUTH.to_si_dict()
    paper = DEMO_TRUTH.to_paper_units()
    with session_exit_codes(console, json_out):
        from fakes.nomad.process import EmulatorProcess

        with tempfile.TemporaryDirectory(prefix="odohil-demo-") as tmp:
            folder = session or Path(tmp) / "session"
            args = [
                "--seed", str(seed),
                "--E-R", repr(paper["E_R"]),
                "--E-T", repr(paper["E_T"]),
                "--K-theta", repr(paper["K_theta"]),
                "--K-rho", repr(paper["K_rho"]),
                "--time-scale", repr(DEMO_TIME_SCALE),
                "--truth-socket", str(Path(tmp) / "truth.sock"),
            ]  # fmt: skip
            with EmulatorProcess(args) as emulator:
                console.print(
                    f"fake robot on {emulator.device}; its true parameters: "
                    f"{parameters_line(truth, system)}",
                    highlight=False,
                )
                description = parse_robot_description(DEMO_ROBOT_TOML, "demo robot")
                baud = robot_facts(description.robot.protocol).default_baud
                settings = {
                    "port": emulator.device,
                    "baud": baud,
                    "truth_socket": emulator.truth_socket,
                    "seed": seed,
                    "truth": truth,
                }
                with session_input(console):
                    journal, state = start_session(
                        folder,
                        DEMO_ROBOT_TOML,
                        parse_plan(DEMO_PLAN),
                        measure="fake",
                        settings=settings,
                    )
                line = resolve_line(description, emulator.device, baud)
                with journal, connect(line, emulator.truth_socket) as (robot, reader):
                    outcome = _calibrate(
                        journal, state, robot, reader, description, seed, settings, console, system
                    )
    _finish(outcome, truth, json_out, console, system)


def _calibrate(
    journal: Journal,
    state: SessionState,
    robot: Robot,
    reader: Any,
    description: RobotDescription,
    seed: int,
    settings: dict[str, Any],
    console: Console,
    system: units.UnitSystem,
) -> Outcome:
    """The session, measured by the fake's truth as a tape with ``seed``'s noise."""
    tape = FakeTruthSource(SnapshotTruth(reader), description, seed=seed)
    source = TapeSource(tape, description)
    return execute(
        journal,
        state,
        robot,
        source,
        settings,
        console,
        system=system,
        measurer="the simulated operator",
    )


def _finish(
    outcome: Outcome,
    truth: dict[str, float],
    json_out: bool,
    console: Console,
    system: units.UnitSystem,
) -> None:
    """Print (or --json) the estimate beside the fake's true values, SI in JSON."""
    extra = {
        "truth": {name: {"value": value, "unit": SI_UNITS[name]} for name, value in truth.items()}
    }
    finish(outcome, json_out, console, extra=extra, truth=truth, system=system)


CREATE2_PLAN = "k=1,l=2,n=12,variant=reverse;k=0.5,l=2,n=12,variant=reverse"
"""Turn-free designs (docs/create2.md): closed 4 m runs and one-way 2 m runs."""
CREATE2_TIME_SCALE = 10.0
"""The fake Create 2's time scale: its legs end on 15 ms readings of the
encoders and a stop sent by the host, so on a faster clock a late reading
ends a leg centimetres long."""
CREATE2_MAX_GAP_MS = 15.0
"""The fake's clock advances at most one 15 ms tick between two calls of the
driver (fakes/create2/clock.py): a host descheduled by a busy machine loses
that time instead of letting the wheels drive through it."""


def _demo_create2(
    seed: int, json_out: bool, session: Path | None, system: units.UnitSystem
) -> None:
    """``--robot create2``: the same job on the fake Create 2 (in process, through
    ``fakecreate2://`` and the real driver), reverse designs only.

    In process rather than on a pty: a Create 2 leg ends when the host's stop
    command arrives, so a fake in another process that a busy machine
    deschedules for 20 ms drives a time-scaled leg centimetres long; in process
    the fake reads each command the moment the driver writes it.
    """
    console = Console(stderr=True)
    truth = DEMO_TRUTH.to_si_dict()
    paper = DEMO_TRUTH.to_paper_units()
    toml = DEMO_ROBOT_TOML + '[robot]\nprotocol = "create2"\n'
    query = "&".join(
        [f"seed={seed}", f"time_scale={CREATE2_TIME_SCALE!r}", f"max_gap_ms={CREATE2_MAX_GAP_MS!r}"]
        + [f"{name}={paper[name]!r}" for name in ("E_R", "E_T", "K_theta", "K_rho")]
    )
    port = f"fakecreate2://?{query}"
    with (
        session_exit_codes(console, json_out),
        tempfile.TemporaryDirectory(prefix="odohil-demo-") as tmp,
    ):
        folder = session or Path(tmp) / "session"
        console.print(
            f"fake Create 2 at {port}; its true parameters: {parameters_line(truth, system)}",
            highlight=False,
        )
        description = parse_robot_description(toml, "demo robot")
        line = resolve_line(description, port, None)
        settings = {"port": port, "baud": line.baud, "seed": seed, "truth": truth}
        with session_input(console):
            journal, state = start_session(
                folder, toml, parse_plan(CREATE2_PLAN), measure="fake", settings=settings
            )
        with journal, connect(line, None) as (robot, reader):
            outcome = _calibrate(
                journal, state, robot, reader, description, seed, settings, console, system
            )
    _finish(outcome, truth, json_out, console, system)


def register(app: typer.Typer) -> None:
    """Add ``demo`` to the ``odohil`` app."""
    app.command("demo")(demo)
