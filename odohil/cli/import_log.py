"""``odohil import LOG... --robot R --out trials.jsonl``: trials from a recorded
log of any path (odometry and ground truth), written as a general-path trial
file (odohil/session/commands/import_log.py; formats in docs/recording.md)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console

from odohil.cli.options import robot_option
from odohil.cli.recording_options import source_options
from odohil.cli.render import bad_inputs, drawn
from odohil.session.commands.import_log import import_recording
from odohil.session.trials.logs import ImportOptions


@source_options(selection=False, exclude=False)
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
        robot_option(
            " Its \\[robot] geometry turns wheel counts into odometry; its "
            "\\[measurement] pose_sigma, if given, is the ground truth's accuracy."
        ),
    ],
    out: Annotated[
        Path, typer.Option("--out", help="The general-path trial file to write (JSON lines).")
    ],
    *,
    recording: ImportOptions,
) -> None:
    """Cut a recording into trials (at rest, or by a trial column or file) and write them.

    Exit 0 with a summary (trials, families, directions, distance); exit 2 on
    a log, option or robot description that cannot be used (nothing written).
    """
    console = Console()
    with bad_inputs(Console(stderr=True)):
        summary = import_recording(logs, robot, recording, out)
    console.print(drawn(summary.table))
    console.print(summary.wrote, highlight=False)
