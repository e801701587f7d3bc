"""TUM trajectory pairs (odohil/session/trials/logs/tum.py), written as the evo tool
writes them (``np.savetxt`` of ``timestamp tx ty tz qx qy qz qw``, space
separated, full precision), associated by time as evo does."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from odohil.errors import RecordingError
from odohil.session.trials.logs import ImportOptions, read_recording
from tests.logs.data import optiodom_robot
from tests.logs.synth import SynthLog, synth_log, varied_motions

TUM = ImportOptions(format="tum")


def write_tum(path: Path, t: np.ndarray, poses: np.ndarray) -> Path:
    """As evo's file_interface.write_tum_trajectory_file: stamps, xyz, quaternion x y z w."""
    half = 0.5 * poses[:, 2]
    zeros = np.zeros(len(t))
    matrix = np.column_stack(
        (t, poses[:, 0], poses[:, 1], zeros, zeros, zeros, np.sin(half), np.cos(half))
    )
    np.savetxt(path, matrix, delimiter=" ")
    return path


def _pair(
    tmp_path: Path, log: SynthLog, *, truth_every: int = 2, truth_shift_s: float = 0.0
) -> list[Path]:
    odom = write_tum(tmp_path / "odom.txt", log.t_s, log.odometry)
    # the capture system runs on its own clock, at another rate, 3 ms off the odometry's
    t_truth = log.t_s[::truth_every] + 0.003 + truth_shift_s
    truth = write_tum(tmp_path / "truth.txt", t_truth, log.truth[::truth_every])
    return [odom, truth]


def test_a_pair_gives_the_motions_between_rests(tmp_path: Path) -> None:
    log = synth_log(varied_motions())
    trials = read_recording(_pair(tmp_path, log), optiodom_robot(), TUM)
    assert [(t.family, t.direction) for t in trials] == [
        ("straight", "forward"),
        ("spin", "cw"),
        ("straight", "backward"),
        ("arc", "ccw"),
    ]
    for trial, true in zip(trials, log.true_changes, strict=True):
        expected = np.array(true) - [0.0, 0.0, trial.path.winding_rad]
        sd = np.sqrt(np.diag(trial.measurement_cov))
        assert np.all(np.abs(trial.pose_change - expected) < 5 * sd + 1e-9)


def test_the_time_offset_brings_another_clock_in(tmp_path: Path) -> None:
    log = synth_log(varied_motions())
    paths = _pair(tmp_path, log, truth_shift_s=1e6)
    with pytest.raises(RecordingError, match=r"odom.txt.*the clocks do not overlap: odometry"):
        read_recording(paths, optiodom_robot(), TUM)
    shifted = ImportOptions(format="tum", time_offset_s=-1e6)
    assert len(read_recording(paths, optiodom_robot(), shifted)) == 4


def test_stamps_further_apart_than_the_max_difference_leave_gaps(tmp_path: Path) -> None:
    log = synth_log(varied_motions())
    paths = _pair(tmp_path, log)
    strict = ImportOptions(format="tum", max_time_diff_s=0.001)  # the 3 ms never match
    with pytest.raises(RecordingError, match=r"ground truth"):
        read_recording(paths, optiodom_robot(), strict)


def test_files_come_in_pairs(tmp_path: Path) -> None:
    paths = _pair(tmp_path, synth_log(varied_motions()))
    with pytest.raises(RecordingError, match=r"TUM files come in pairs .* got 3 files"):
        read_recording([*paths, paths[0]], optiodom_robot(), TUM)


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda lines: lines[4].rsplit(" ", 1)[0], r"line 5: 7 fields; a TUM line has 8"),
        (lambda lines: lines[3], r"line 5: timestamp must increase"),
        (lambda lines: lines[4].rsplit(" ", 1)[0] + " 2.0", r"line 5: qx qy qz qw: not a unit"),
        (lambda lines: lines[4].replace(lines[4].split()[1], "nan"), r"line 5: tx: not a finite"),
    ],
)
def test_a_bad_line_names_the_line_and_the_field(tmp_path: Path, edit, message: str) -> None:
    paths = _pair(tmp_path, synth_log(varied_motions()))
    lines = paths[1].read_text().splitlines()
    lines[4] = edit(lines)
    paths[1].write_text("\n".join(lines) + "\n")
    with pytest.raises(RecordingError, match=rf"truth.txt {message}"):
        read_recording(paths, optiodom_robot(), TUM)


def test_headings_come_from_the_quaternion_about_z(tmp_path: Path) -> None:
    from odohil.session.trials.logs.tum import heading_of

    for angle in (-3.0, -1.0, 0.0, 0.5, 3.1):
        assert math.isclose(heading_of(0.0, 0.0, math.sin(angle / 2), math.cos(angle / 2)), angle)


def test_a_stretch_without_ground_truth_is_a_gap(tmp_path: Path) -> None:
    log = synth_log(varied_motions())
    paths = _pair(tmp_path, log)
    lines = paths[1].read_text().splitlines()
    del lines[200:240]  # 1.6 s of the capture lost during the first run
    paths[1].write_text("\n".join(lines) + "\n")
    with pytest.raises(
        RecordingError,
        match=r"odom.txt \(ground truth truth.txt\) line \d+: tx ty qz qw \(ground "
        r"truth\): a gap in the ground truth of 1.6\d* s",
    ):
        read_recording(paths, optiodom_robot(), TUM)
