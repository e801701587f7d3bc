"""``odohil demo``: a whole calibration against a fake robot, unattended.

The fake robot of the chosen backend runs in process behind its pyserial URL
(``fakerobot://``, ``fakecreate2://``: the scheme its backend declares,
odohil/session/robots.py ``fake_hooks``) with known, exaggerated error
parameters (:data:`DEMO_TRUTH`); the session lifecycle runs it through the
real driver with the fake's ground truth as measurement source (1 mm tape
noise), and the estimates are printed beside the true values.
"""

from __future__ import annotations

import tempfile
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console

from odohil.cli.options import UNITS_DEFAULT, UnitsOption, bounded, unit_system
from odohil.cli.render import parameters_line
from odohil.cli.robot_option import robot_protocol
from odohil.cli.session_view import (
    finish,
    prepared_or_exit,
    report_run,
    run_with_progress,
    session_exit_codes,
)
from odohil.science.parameters import SI_UNITS, ErrorParameters
from odohil.session.lifecycle import SessionSpec, open_session, preflight
from odohil.session.robots import backend_names, robot_facts

DEMO_TRUTH = ErrorParameters.from_paper_units(-1.0, -0.05, 0.3, 9e-4)
"""The fake robot's true parameters: the Nomad 150's (-0.202 deg/m, -0.02,
0.012 deg^2/m, 3.6e-5 m) scaled by about 5, 2.5, 25 and 25, so that the
odometry error of a 4 m trial stands well clear of 1 mm tape noise."""
DEMO_PLAN = "k=1,l=2,n=24;k=0.5,l=2,n=24"
"""Closed 4 m runs (E_R, K_theta, K_rho) and one-way 2 m runs (E_T)."""
TURN_FREE_PLAN = "k=1,l=2,n=12,variant=reverse;k=0.5,l=2,n=12,variant=reverse"
"""For a robot whose turns carry error (docs/create2.md): closed 4 m runs and
one-way 2 m runs, turn-free; fewer trials, as its fake runs on a slower clock."""
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
    protocol = robot_protocol(robot_name)
    facts = robot_facts(protocol)
    if facts.fake is None:
        demoable = [name for name in backend_names() if robot_facts(name).fake is not None]
        raise typer.BadParameter(
            f"one of {', '.join(demoable)} (a backend with a fake robot); got {protocol!r}",
            param_hint="--robot",
        )
    plan = DEMO_PLAN if facts.turns_exact else TURN_FREE_PLAN
    options = {"time_scale": facts.fake.demo_time_scale, **dict(facts.fake.demo_url_options)}
    console = Console(stderr=True)
    truth = DEMO_TRUTH.to_si_dict()
    paper = DEMO_TRUTH.to_paper_units()
    query = "&".join(
        [f"seed={seed}", *(f"{name}={value!r}" for name, value in options.items())]
        + [f"{name}={paper[name]!r}" for name in ("E_R", "E_T", "K_theta", "K_rho")]
    )
    port = f"{facts.fake.url_scheme}//?{query}"
    toml = DEMO_ROBOT_TOML + f'[robot]\nprotocol = "{protocol}"\n'
    with (
        session_exit_codes(console, json_out),
        tempfile.TemporaryDirectory(prefix="odohil-demo-") as tmp,
    ):
        spec = SessionSpec(
            session or Path(tmp) / "session", "new", robot_toml=toml, plan=plan,
            measure="fake", port=port, seed=seed, settings={"truth": truth},
        )  # fmt: skip
        prepared = prepared_or_exit(preflight(spec), console)
        console.print(
            f"fake robot at {port}; its true parameters: {parameters_line(truth, system)}",
            highlight=False,
        )
        with open_session(prepared) as opened:
            outcome = run_with_progress(console, opened, system)
            report_run(console, outcome)
    extra = {"truth": {name: {"value": v, "unit": SI_UNITS[name]} for name, v in truth.items()}}
    finish(outcome, json_out, console, extra=extra, truth=truth, system=system)


def register(app: typer.Typer) -> None:
    """Add ``demo`` to the ``odohil`` app."""
    app.command("demo")(demo)
