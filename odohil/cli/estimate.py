"""``odohil estimate FILE|SESSION``: the four parameters from a trial file or a
session folder, with checks."""

from __future__ import annotations

import json
from collections.abc import Sequence
from enum import StrEnum
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console

from odohil.cli.exit_codes import exit_for_outcome
from odohil.cli.options import UNITS_DEFAULT, JsonOption, UnitsOption, robot_option, unit_system
from odohil.cli.recording_options import source_options
from odohil.cli.render import bad_inputs, print_outcome, torn_warning
from odohil.session.results.outcome import EstimateOutcome, Selection, estimate_source
from odohil.session.robots.description import load_robot_description
from odohil.session.trials.logs import ImportOptions

SOURCES_HELP = (
    "A session folder; a trial file (pose rows or raw floor marks; a general-path trial "
    "file of `odohil import`); or a recording `odohil import` reads (odohil log CSVs, TUM "
    "files in pairs, ROS 2 bags, optiodom run files or folders; needs --robot)."
)


class MethodChoice(StrEnum):
    """The estimator."""

    robust = "robust"
    joint = "joint"
    paper = "paper"


def load_outcome(
    sources: Sequence[Path],
    robot: Path | None,
    exclude: frozenset[int],
    err: Console,
    method: str = "robust",
    recording: ImportOptions | None = None,
    selection: Selection | None = None,
) -> EstimateOutcome:
    """The one recipe's outcome of a source (session folder, trial file or
    recording: :func:`odohil.session.results.outcome.estimate_source`); a torn last
    journal record is reported on ``err``; any bad input exits 2 (said on ``err``)."""
    with bad_inputs(err):
        description = load_robot_description(robot) if robot is not None else None
        outcome = estimate_source(sources, description, exclude, method, recording, selection)
    torn_warning(outcome, err)
    return outcome


@source_options()
def estimate(
    sources: Annotated[list[Path], typer.Argument(help=SOURCES_HELP)],
    robot: Annotated[
        Path | None,
        robot_option(
            " Needed for raw marks and recordings; its \\[robot] turns_exact = false fits "
            "the turn errors e_turn (and K_spin) on general paths."
        ),
    ] = None,
    method: Annotated[
        MethodChoice,
        typer.Option(
            "--method",
            help="robust (maximum likelihood with a per-trial outlier probability), "
            "joint (Gaussian maximum likelihood) or paper.",
        ),
    ] = MethodChoice.robust,
    as_json: JsonOption = False,
    units_choice: UnitsOption = UNITS_DEFAULT,
    *,
    exclude: frozenset[int],
    recording: ImportOptions,
    selection: Selection,
) -> None:
    """Estimate E_R, E_T, K_theta, K_rho (and a differential drive's e_turn,
    K_spin) from a session folder, a trial file or a recording.

    Exit status 0 when the verdict is trusted, 3 when the estimate is
    printed but doubtful or failed or the trials give none (too few, or
    all left out), 2 on a bad file (every bad row listed by line) or a
    bad --exclude.
    """
    err = Console(stderr=True)
    outcome = load_outcome(sources, robot, exclude, err, method.value, recording, selection)
    if as_json:
        typer.echo(json.dumps(outcome.to_json_dict(), indent=2))
    else:
        out = Console(width=max(120, Console().width))
        print_outcome(out, outcome, unit_system(units_choice), "odometry error parameters")
    raise typer.Exit(exit_for_outcome(outcome))
