"""``odohil demo``: a whole calibration against a fake robot, unattended.

The fake robot of the chosen backend runs in process with known, exaggerated
error parameters; the session lifecycle runs it through the real driver with
the fake's ground truth as measurement source (odohil/session/commands/demo.py), and
the estimates are printed beside the true values.
"""

from __future__ import annotations

import tempfile
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console

from odohil.cli.options import (
    UNITS_DEFAULT,
    UnitsOption,
    option,
    unit_system,
    usage_errors,
)
from odohil.cli.session_view import drive, finish
from odohil.session.commands.demo import demo_session
from odohil.session.robots.description import robot_protocol
from odohil.session.run import Opened

_ROBOT_HELP = (
    "Which fake robot: nomad150 or create2, or a robot description file whose "
    "\\[robot] protocol is one of them (docs/create2.md)."
)


def demo(
    seed: Annotated[
        int, option("--seed", bound="seed", help="Seed of the fake robot and tape.")
    ] = 1,
    json_out: Annotated[
        bool, typer.Option("--json", help="Print the estimate and the truth as JSON.")
    ] = False,
    session: Annotated[
        Path | None,
        typer.Option("--session", help="Keep the session folder here (default: a temp folder)."),
    ] = None,
    units_choice: UnitsOption = UNITS_DEFAULT,
    robot_name: Annotated[str, typer.Option("--robot", help=_ROBOT_HELP)] = "nomad150",
) -> None:
    """Calibrate the fake robot unattended and compare with its true parameters.

    The simulated operator measures with a 1 mm tape; when its distances fit no
    rigid motion (or one looks like a slip) it measures again, as a person
    would, and the demo says so.
    """
    system = unit_system(units_choice)
    console = Console(stderr=True)
    with tempfile.TemporaryDirectory(prefix="odohil-demo-") as tmp:
        with usage_errors("--robot"):
            made = demo_session(robot_protocol(robot_name), seed, session or Path(tmp) / "session")

        def say(opened: Opened) -> None:
            console.print(made.heading(system), highlight=False)

        outcome = drive(console, made.spec, system, json_out, say)
    finish(outcome, json_out, console, extra=made.truth_document(), truth=made.truth, system=system)
