"""``odohil import LOG... --robot R --out trials.jsonl``: trials from a recorded
log of any path (odometry and ground truth), written as a general-path trial
file (odohil/session/path_trial_file.py; formats in docs/recording.md)."""

from __future__ import annotations

from enum import StrEnum
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console
from rich.table import Table

from odohil.cli.exit_codes import EXIT_BAD_INPUT
from odohil.cli.robot_option import ROBOT_HELP, robot_callback
from odohil.errors import OdohilError
from odohil.science.rest_cutting import MIN_EDGE_REST_S, MIN_REST_S
from odohil.session.logs import ImportOptions, read_recording
from odohil.session.logs.recording import (
    DEFAULT_MAX_TIME_DIFF_S,
    MAX_TRUTH_GAP_S,
)
from odohil.session.path_trial_file import summary_rows, write_path_trials
from odohil.session.robot_file import load_robot_description


class FormatChoice(StrEnum):
    """The log formats ``import`` reads."""

    csv = "csv"
    tum = "tum"
    rosbag = "rosbag"
    optiodom = "optiodom"


def import_log(
    logs: Annotated[
        list[Path],
        typer.Argument(
            help="Log files: odohil CSV logs; TUM files in pairs (odometry, ground truth); "
            "ROS 2 bags (folders or .mcap/.db3 files); optiodom run files or folders."
        ),
    ],
    robot: Annotated[
        Path,
        typer.Option(
            "--robot",
            callback=robot_callback,
            help=ROBOT_HELP + " Its [robot] geometry turns wheel counts into odometry; its "
            "[measurement] pose_sigma, if given, is the ground truth's accuracy.",
        ),
    ],
    out: Annotated[
        Path, typer.Option("--out", help="The general-path trial file to write (JSON lines).")
    ],
    log_format: Annotated[
        FormatChoice | None,
        typer.Option("--format", help="The log format (default: guessed from the paths)."),
    ] = None,
    odom_topic: Annotated[
        str, typer.Option("--odom-topic", help="Bags: the odometry topic (nav_msgs/msg/Odometry).")
    ] = "/odom",
    truth_topic: Annotated[
        str,
        typer.Option(
            "--truth-topic",
            help="Bags: the ground-truth topic (geometry_msgs/msg/PoseStamped or "
            "nav_msgs/msg/Odometry).",
        ),
    ] = "/ground_truth",
    max_time_diff: Annotated[
        float,
        typer.Option(
            "--max-time-diff",
            help="TUM, bags: largest stamp difference of an odometry and ground-truth pair, s.",
        ),
    ] = DEFAULT_MAX_TIME_DIFF_S,
    time_offset: Annotated[
        float,
        typer.Option("--time-offset", help="TUM, bags: added to the ground truth's stamps, s."),
    ] = 0.0,
    min_rest: Annotated[
        float, typer.Option("--min-rest", help="Shortest rest between two trials, s.")
    ] = MIN_REST_S,
    min_edge_rest: Annotated[
        float,
        typer.Option(
            "--min-edge-rest",
            help="Shortest rest at either end of a trial cut by a trial column or file, s.",
        ),
    ] = MIN_EDGE_REST_S,
    max_truth_gap: Annotated[
        float,
        typer.Option("--max-truth-gap", help="Longest time without ground truth in a trial, s."),
    ] = MAX_TRUTH_GAP_S,
) -> None:
    """Cut a recording into trials (at rest, or by a trial column or file) and write them.

    Exit 0 with a summary (trials, families, directions, distance); exit 2 on
    a log, option or robot description that cannot be used (nothing written).
    """
    console = Console()
    err = Console(stderr=True)
    try:
        options = ImportOptions(
            format=None if log_format is None else log_format.value,
            odom_topic=odom_topic,
            truth_topic=truth_topic,
            max_time_diff_s=max_time_diff,
            time_offset_s=time_offset,
            min_rest_s=min_rest,
            min_edge_rest_s=min_edge_rest,
            max_truth_gap_s=max_truth_gap,
        )
        description = load_robot_description(robot)
        trials = read_recording(logs, description, options)
        written = write_path_trials(out, trials, robot=robot.stem)
    except (OdohilError, OSError) as exc:
        err.print(f"[red]error:[/red] {exc}", highlight=False)
        raise typer.Exit(EXIT_BAD_INPUT) from None
    table = Table(title=f"{written} trials from {len(logs)} log path(s)")
    table.add_column("family")
    table.add_column("direction")
    table.add_column("trials", justify="right")
    table.add_column("distance (m)", justify="right")
    for family, direction, count, distance in summary_rows(trials):
        table.add_row(family, direction, str(count), f"{distance:.3f}")
    console.print(table)
    total = sum(trial.path.distance_m for trial in trials)
    console.print(f"wrote {written} trials ({total:.3f} m driven) to {out}", highlight=False)


def register(app: typer.Typer) -> None:
    """Add ``import`` to the ``odohil`` app."""
    app.command("import")(import_log)
