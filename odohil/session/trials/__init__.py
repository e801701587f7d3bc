"""Trials from files: what a calibration reads when no robot drives.

- trial_file.py: the CSV trial file (:class:`Trial`, :class:`TrialSet`, ``read_trials``);
- path_trial_file.py: the general-path trial file (JSON lines);
- pose_file.py: pose files serving driven paths, and ``check_trial_file``;
- logs/: recorded logs of any path, one module per format (its own face).
"""

from odohil.session.trials.path_trial_file import (
    is_path_trial_file,
    read_path_trials,
    summary_rows,
    write_path_trials,
)
from odohil.session.trials.pose_file import (
    PoseRow,
    check_trial_file,
    file_format,
    read_path_rows,
    read_pose_file,
    read_rows,
    refuse_rows,
    row_problem,
    steps_problem,
)
from odohil.session.trials.trial_file import Trial, TrialSet, read_trials, write_pose_trials

__all__ = [
    "PoseRow",
    "Trial",
    "TrialSet",
    "check_trial_file",
    "file_format",
    "is_path_trial_file",
    "read_path_rows",
    "read_path_trials",
    "read_pose_file",
    "read_rows",
    "read_trials",
    "refuse_rows",
    "row_problem",
    "steps_problem",
    "summary_rows",
    "write_path_trials",
    "write_pose_trials",
]
