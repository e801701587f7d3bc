"""What ``odohil import`` does: a recording read and cut into trials with a
robot description (odohil/session/trials/logs/), written as a general-path trial
file (odohil/session/trials/path_trial_file.py), and the summary it tells of them."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from odohil import units
from odohil.session.robots.description import load_robot_description
from odohil.session.table_text import TableText
from odohil.session.trials.logs import ImportOptions, guess_format, read_cut
from odohil.session.trials.path_trial_file import summary_rows, write_path_trials

__all__ = [
    "import_recording",
]


@dataclass(frozen=True)
class ImportSummary:
    """What was imported.

    Attributes:
        table: ``12 trials from 2 log paths, read as tum``: per path family
            and direction the trials and the distance driven, m.
        wrote: ``wrote 12 trials (20.965 m driven) to FILE``, and with
            ``--window-m`` how the windows went (odohil/session/text/outcome.py
            ``WindowCount.lines``) on the lines after.
    """

    table: TableText
    wrote: str


def import_recording(
    logs: Sequence[Path], robot: Path, recording: ImportOptions, out: Path
) -> ImportSummary:
    """Read the recording ``logs`` with the robot description ``robot``, cut
    it into trials, write them to ``out``; what was written.

    Raises:
        RecordingError, RobotDescriptionError, ParameterError, OSError: a log,
            option or description that cannot be used (nothing written).
    """
    description = load_robot_description(robot)
    cut = read_cut(logs, description, recording)
    trials = list(cut.trials)
    written = write_path_trials(out, trials, robot=robot.stem)
    read_as = recording.format or guess_format(logs)
    title = f"{units.plural(written, 'trial')} from {units.plural(len(logs), 'log path')}"
    rows = [
        (family, direction, str(count), f"{distance:.3f}")
        for family, direction, count, distance in summary_rows(trials)
    ]
    total = sum(trial.path.distance_m for trial in trials)
    wrote = f"wrote {units.plural(written, 'trial')} ({total:.3f} m driven) to {out}"
    if cut.windows is not None:
        wrote = "\n".join([wrote, *cut.windows.lines()])
    columns = ("family", "direction", "trials", "distance (m)")
    table = TableText(f"{title}, read as {read_as}", columns, rows, ("family", "direction"))
    return ImportSummary(table, wrote)
