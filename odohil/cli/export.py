"""``odohil export SESSION|FILE --format F``: the estimate as a fusion stack's configuration."""

from __future__ import annotations

from enum import StrEnum
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console
from rich.markup import escape

from odohil.cli.estimate import SOURCES_HELP, load_outcome
from odohil.cli.exclude import EXCLUDE_HELP, parse_exclude
from odohil.cli.exit_codes import EXIT_BAD_INPUT, EXIT_UNTRUSTED
from odohil.cli.options import bounded
from odohil.cli.recording_options import (
    MAX_TIME_DIFF_DEFAULT,
    MAX_TRUTH_GAP_DEFAULT,
    MIN_EDGE_REST_DEFAULT,
    MIN_REST_DEFAULT,
    ODOM_TOPIC_DEFAULT,
    TRUTH_TOPIC_DEFAULT,
    DirectionOption,
    FamilyOption,
    LogFormatOnlyOption,
    MaxTimeDiffOption,
    MaxTruthGapOption,
    MinEdgeRestOption,
    MinRestOption,
    OdomTopicOption,
    TimeOffsetOption,
    TruthTopicOption,
    import_options,
)
from odohil.cli.robot_option import ROBOT_HELP, robot_callback
from odohil.cli.verdict import export_refusal_lines, outcome_line
from odohil.errors import OdohilError
from odohil.science.exports import (
    DEFAULT_RATE_HZ,
    DEFAULT_UPDATE_MIN_A_RAD,
    DEFAULT_UPDATE_MIN_D_M,
    Linearisation,
)
from odohil.science.limits import RANGES
from odohil.science.planner import DEFAULT_SPEED_M_PER_S
from odohil.session.exports import export_text
from odohil.session.outcome import Selection

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


def export(
    sources: Annotated[list[Path], typer.Argument(help=SOURCES_HELP)],
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
            "--robot",
            callback=robot_callback,
            help=ROBOT_HELP + " Needed for raw marks and recordings.",
        ),
    ] = None,
    exclude: Annotated[str | None, typer.Option("--exclude", help=EXCLUDE_HELP)] = None,
    family: FamilyOption = None,
    direction: DirectionOption = None,
    log_format: LogFormatOnlyOption = None,
    odom_topic: OdomTopicOption = ODOM_TOPIC_DEFAULT,
    truth_topic: TruthTopicOption = TRUTH_TOPIC_DEFAULT,
    max_time_diff: MaxTimeDiffOption = MAX_TIME_DIFF_DEFAULT,
    time_offset: TimeOffsetOption = 0.0,
    min_rest: MinRestOption = MIN_REST_DEFAULT,
    min_edge_rest: MinEdgeRestOption = MIN_EDGE_REST_DEFAULT,
    max_truth_gap: MaxTruthGapOption = MAX_TRUTH_GAP_DEFAULT,
) -> None:
    """Write the estimate in the shape a fusion stack takes (docs/exports.md).

    An estimate that is not trusted, none at all, or one too imprecise to
    export (a design below the planner's minimum trials, a correction whose
    95 % interval is wider than itself) is refused (exit 3, nothing
    written) unless --force (no estimate is refused even then); exit 2 on
    bad input.
    """
    lin = Linearisation(speed, rate_hz, update_min_d, update_min_a)
    err = Console(stderr=True)
    try:
        recording = import_options(
            log_format,
            odom_topic,
            truth_topic,
            max_time_diff,
            time_offset,
            min_rest,
            min_edge_rest,
            max_truth_gap,
        )
        outcome = load_outcome(
            sources,
            robot,
            parse_exclude(exclude),
            err,
            recording=recording,
            selection=Selection(family, direction),
        )
    except (OdohilError, OSError) as exc:
        err.print(f"[red]error:[/red] {escape(str(exc))}", highlight=False)
        raise typer.Exit(EXIT_BAD_INPUT) from None
    result = outcome.result
    if result is None:
        err.print(outcome_line(outcome), highlight=False)
        err.print("[red]refused:[/red] no estimate to export; nothing written.", highlight=False)
        raise typer.Exit(EXIT_UNTRUSTED)
    err.print(outcome_line(outcome), highlight=False)
    if not outcome.exportable and not force:
        for line in export_refusal_lines(outcome):
            err.print(line, highlight=False)
        err.print(
            "[red]refused:[/red] the estimate is not "
            + ("trusted" if not outcome.trusted else "precise enough to export")
            + "; nothing written. Fix the trials (or leave them out with --exclude N,...), "
            "add trials, or pass --force to export it with the verdict stated in the file.",
            highlight=False,
        )
        raise typer.Exit(EXIT_UNTRUSTED)
    try:
        text = export_text(fmt.value, result, lin, source=sources[0].name)
    except OdohilError as exc:
        err.print(f"[red]error:[/red] {escape(str(exc))}", highlight=False)
        raise typer.Exit(EXIT_BAD_INPUT) from None
    if out is None:
        typer.echo(text, nl=False)
    else:
        try:
            out.write_text(text, encoding="utf-8")
        except OSError as exc:
            err.print(f"[red]error:[/red] {escape(str(exc))}", highlight=False)
            raise typer.Exit(EXIT_BAD_INPUT) from None
        err.print(f"wrote {out} ({fmt.value})", highlight=False)
    if not outcome.exportable:
        err.print("exported with --force although refused without it", highlight=False)


def register(app: typer.Typer) -> None:
    """Add ``export`` to the ``odohil`` app."""
    app.command("export")(export)
