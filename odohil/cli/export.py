"""``odohil export SESSION|FILE --format F``: the estimate as a fusion stack's configuration."""

from __future__ import annotations

from enum import StrEnum
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console

from odohil.cli.estimate import observation_of
from odohil.cli.exclude import EXCLUDE_HELP, check_exclude, parse_exclude
from odohil.cli.exit_codes import EXIT_BAD_INPUT, EXIT_UNTRUSTED
from odohil.cli.options import bounded
from odohil.cli.robot_option import ROBOT_HELP, robot_callback, turns_exact_of
from odohil.cli.verdict import verdict_line
from odohil.errors import OdohilError
from odohil.science.estimators import EstimateResult, estimate
from odohil.science.exports import (
    DEFAULT_RATE_HZ,
    DEFAULT_UPDATE_MIN_A_RAD,
    DEFAULT_UPDATE_MIN_D_M,
    Linearisation,
)
from odohil.science.limits import RANGES
from odohil.science.planner import DEFAULT_SPEED_M_PER_S
from odohil.session.exports import export_text
from odohil.session.robot_file import load_robot_description
from odohil.session.state import load_session_trials
from odohil.session.trial_files import read_trials

SPEED_RANGE = RANGES["speed"]
RATE_RANGE = RANGES["rate_hz"]
UPDATE_D_RANGE = RANGES["update_min_d_m"]
UPDATE_A_RANGE = RANGES["update_min_a_rad"]


class FormatChoice(StrEnum):
    """The export formats (docs/exports.md)."""

    ros2_diff_drive = "ros2-diff-drive"
    odometry_msg = "odometry-msg"
    robot_localization = "robot-localization"
    amcl = "amcl"
    json = "json"


def load_estimate(source: Path, robot: Path | None, exclude: frozenset[int]) -> EstimateResult:
    """The default (robust) estimate of a session folder or a trial file, as
    ``odohil estimate`` makes it (ambiguous trials left out and named).

    Raises:
        OdohilError: unreadable source, no trials, or a bad --exclude.
    """
    if source.is_dir():
        trials = load_session_trials(source)
    else:
        description = load_robot_description(robot) if robot is not None else None
        trials = read_trials(source, description)
    if len(trials) == 0:
        raise OdohilError(f"{source}: no trials")
    rows = sorted((*trials.trials, *trials.ambiguous), key=lambda t: t.line)
    position = {t.line: i for i, t in enumerate(rows)}
    observations = [observation_of(t, position[t.line]) for t in trials.trials]
    ambiguous = [
        t.number if t.number is not None else position[t.line] + 1 for t in trials.ambiguous
    ]
    check_exclude(exclude, [o.trial for o in observations if o.trial is not None])
    turns_exact = turns_exact_of(source, robot)
    return estimate(observations, exclude=exclude, ambiguous=ambiguous, turns_exact=turns_exact)


def export(
    source: Annotated[
        Path, typer.Argument(help="A session folder, or a trial file (raw marks need --robot).")
    ],
    fmt: Annotated[
        FormatChoice,
        typer.Option(
            "--format", help="ros2-diff-drive, odometry-msg, robot-localization, amcl, json."
        ),
    ],
    speed: Annotated[
        float,
        typer.Option(
            "--speed",
            callback=bounded("speed"),
            help=f"Driving speed the constants are linearised at, m/s, {SPEED_RANGE.text()}.",
        ),
    ] = DEFAULT_SPEED_M_PER_S,
    rate_hz: Annotated[
        float,
        typer.Option(
            "--rate-hz",
            callback=bounded("rate_hz"),
            help=f"Odometry publication rate, Hz (one step = speed / rate), {RATE_RANGE.text()}.",
        ),
    ] = DEFAULT_RATE_HZ,
    update_min_d: Annotated[
        float,
        typer.Option(
            "--update-min-d-m",
            callback=bounded("update_min_d_m"),
            help=f"AMCL's update distance, m, {UPDATE_D_RANGE.text()}.",
        ),
    ] = DEFAULT_UPDATE_MIN_D_M,
    update_min_a: Annotated[
        float,
        typer.Option(
            "--update-min-a-rad",
            callback=bounded("update_min_a_rad"),
            help=f"AMCL's update angle, rad, {UPDATE_A_RANGE.text()}.",
        ),
    ] = DEFAULT_UPDATE_MIN_A_RAD,
    out: Annotated[
        Path | None, typer.Option("--out", help="File to write (default: standard output).")
    ] = None,
    force: Annotated[
        bool,
        typer.Option(
            "--force",
            help="Export an estimate that is not trusted (the file then states its verdict).",
        ),
    ] = False,
    robot: Annotated[
        Path | None,
        typer.Option(
            "--robot", callback=robot_callback, help=ROBOT_HELP + " Needed for raw marks."
        ),
    ] = None,
    exclude: Annotated[str | None, typer.Option("--exclude", help=EXCLUDE_HELP)] = None,
) -> None:
    """Write the estimate in the shape a fusion stack takes (docs/exports.md).

    An estimate that is not trusted is refused (exit 3, nothing written)
    unless --force; exit 2 on bad input.
    """
    lin = Linearisation(speed, rate_hz, update_min_d, update_min_a)
    err = Console(stderr=True)
    try:
        result = load_estimate(source, robot, parse_exclude(exclude))
    except (OdohilError, OSError) as exc:
        err.print(f"[red]error:[/red] {exc}", highlight=False)
        raise typer.Exit(EXIT_BAD_INPUT) from None
    if not result.verdict.trusted and not force:
        err.print(verdict_line(result.verdict), highlight=False)
        err.print(
            "[red]refused:[/red] the estimate is not trusted; nothing written. Fix the trials "
            "(or leave them out with --exclude N,...), or pass --force to export it with the "
            "verdict stated in the file.",
            highlight=False,
        )
        raise typer.Exit(EXIT_UNTRUSTED)
    try:
        text = export_text(fmt.value, result, lin, source=source.name)
    except OdohilError as exc:
        err.print(f"[red]error:[/red] {exc}", highlight=False)
        raise typer.Exit(EXIT_BAD_INPUT) from None
    if out is None:
        typer.echo(text, nl=False)
    else:
        try:
            out.write_text(text, encoding="utf-8")
        except OSError as exc:
            err.print(f"[red]error:[/red] {exc}", highlight=False)
            raise typer.Exit(EXIT_BAD_INPUT) from None
        err.print(f"wrote {out} ({fmt.value})", highlight=False)
    if not result.verdict.trusted:
        err.print(verdict_line(result.verdict) + " (exported with --force)", highlight=False)


def register(app: typer.Typer) -> None:
    """Add ``export`` to the ``odohil`` app."""
    app.command("export")(export)
