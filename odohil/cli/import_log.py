"""``odohil import LOG... --robot R --out trials.jsonl``: trials from a recorded
log of any path (odometry and ground truth), written as a general-path trial
file (odohil/session/path_trial_file.py; formats in docs/recording.md)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console

from odohil import units
from odohil.cli.options import robot_option
from odohil.cli.recording_options import source_options
from odohil.cli.render import bad_inputs, table
from odohil.session.logs import ImportOptions, guess_format, read_recording
from odohil.session.path_trial_file import summary_rows, write_path_trials
from odohil.session.robot_file import load_robot_description


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
    err = Console(stderr=True)
    with bad_inputs(err):
        description = load_robot_description(robot)
        trials = read_recording(logs, description, recording)
        written = write_path_trials(out, trials, robot=robot.stem)
    read_as = recording.format or guess_format(logs)
    title = f"{units.plural(written, 'trial')} from {units.plural(len(logs), 'log path')}"
    columns = ("family", "direction", "trials", "distance (m)")
    summary = table(f"{title}, read as {read_as}", columns, ("family", "direction"))
    for family, direction, count, distance in summary_rows(trials):
        summary.add_row(family, direction, str(count), f"{distance:.3f}")
    console.print(summary)
    total = sum(trial.path.distance_m for trial in trials)
    console.print(
        f"wrote {units.plural(written, 'trial')} ({total:.3f} m driven) to {out}", highlight=False
    )
