"""odohil's log CSV (odohil/session/trials/logs/csv_log.py): written with the csv
module as odohil writes it, cut at rest or by a trial column, and refused
with the file, line and field when it cannot be used."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from odohil.errors import RecordingError
from odohil.science.robot_description import RobotDescription
from odohil.session.robots.description import load_robot_description
from odohil.session.trials.logs import ImportOptions, read_recording
from odohil.session.trials.logs.csv_log import write_csv_log
from odohil.session.trials.logs.optiodom import joined_runs, read_run
from odohil.session.trials.logs.recording import Recording
from tests.logs.data import OPTIODOM, needs_optiodom, optiodom_robot
from tests.logs.synth import Motion, SynthLog, rest, synth_log, varied_motions

CSV = ImportOptions(format="csv")


def _recording(log: SynthLog, trial: tuple[str, ...] | None = None) -> Recording:
    lines = np.arange(2, 2 + len(log.t_s))
    return Recording("synthetic", log.t_s, log.odometry, log.truth, lines, trial=trial)


def _write(tmp_path: Path, log: SynthLog, trial: tuple[str, ...] | None = None) -> Path:
    path = tmp_path / "log.csv"
    write_csv_log(path, _recording(log, trial))
    return path


def _robot(tmp_path: Path, extra: str = "") -> RobotDescription:
    path = tmp_path / "robot.toml"
    text = (
        '[robot]\nprotocol = "recorded"\ncounts_per_rev = 1000\n'
        "wheel_diameter_m = [0.1, 0.1002]\nwheel_base_m = 0.25\n"
        "[screws]\nA = [0.1, 0.0]\nB = [-0.05, 0.08]\nC = [-0.05, -0.08]\n"
        f"[measurement]\nsigma_m = 0.001\n{extra}"
    )
    path.write_text(text)
    return load_robot_description(path)


def test_a_log_cut_at_rest_gives_each_motion_its_true_pose_change(tmp_path: Path) -> None:
    log = synth_log(varied_motions())
    trials = read_recording([_write(tmp_path, log)], _robot(tmp_path), CSV)
    assert [(t.family, t.direction) for t in trials] == [
        ("straight", "forward"),
        ("spin", "cw"),
        ("straight", "backward"),
        ("arc", "ccw"),
    ]
    for trial, true in zip(trials, log.true_changes, strict=True):
        expected = np.array(true) - [0.0, 0.0, trial.path.winding_rad]
        sd = np.sqrt(np.diag(trial.measurement_cov))
        # the rests average 100 poses of 0.1 mm / 1 mrad jitter
        assert np.all(np.abs(trial.pose_change - expected) < 5 * sd + 1e-9)
        assert np.all(sd < [3e-4, 3e-4, 3e-4])
        assert trial.source.endswith("log.csv")
        assert trial.span_s is not None
    assert [t.trial for t in trials] == [1, 2, 3, 4]


def test_pose_sigma_of_the_description_is_the_rest_poses_covariance(tmp_path: Path) -> None:
    log = synth_log(varied_motions()[:3])
    robot = _robot(tmp_path, "pose_sigma = [0.0005, 0.0005, 0.002]\n")
    (trial,) = read_recording([_write(tmp_path, log)], robot, CSV)
    # two rests, each 0.5 mm and 2 mrad; the start heading's error moves the 1 m end sideways
    assert math.isclose(trial.measurement_cov[0, 0], 2 * 0.0005**2, rel_tol=1e-3)
    assert math.isclose(trial.measurement_cov[2, 2], 2 * 0.002**2)
    assert math.isclose(
        trial.measurement_cov[1, 1], 2 * 0.0005**2 + 1.01**2 * 0.002**2, rel_tol=1e-2
    )


def test_a_trial_column_cuts_without_rests_between_trials(tmp_path: Path) -> None:
    motions = [rest(0.5), Motion(3.0, v=0.2), rest(0.5), rest(0.5), Motion(3.0, w=0.9), rest(0.5)]
    log = synth_log(motions)
    half = len(log.t_s) // 2
    labels = ("a",) * half + ("b",) * (len(log.t_s) - half)
    # the rests of 1 s between the two motions are too short to cut at rest
    with pytest.raises(RecordingError, match="never at rest"):
        read_recording([_write(tmp_path, log)], _robot(tmp_path), CSV)
    trials = read_recording([_write(tmp_path, log, labels)], _robot(tmp_path), CSV)
    assert [(t.family, t.direction) for t in trials] == [("straight", "forward"), ("spin", "ccw")]


def test_wheel_counts_with_two_wheel_diameters_give_the_odometry(tmp_path: Path) -> None:
    robot = _robot(tmp_path)
    log = synth_log(varied_motions())
    base = robot.robot.drive.wheel_base_m
    left_per, right_per = robot.robot.drive.wheel_metres_per_count
    # wheel travels of the odometry's own increments (exact arcs), as counts
    d = np.diff(log.odometry, axis=0)
    dtheta = d[:, 2]
    mid = log.odometry[:-1, 2] + 0.5 * dtheta
    chord = np.cos(mid) * d[:, 0] + np.sin(mid) * d[:, 1]
    ds = chord / np.sinc(dtheta / (2 * math.pi))
    left = np.concatenate([[0.0], np.cumsum(ds - 0.5 * base * dtheta)]) / left_per
    right = np.concatenate([[0.0], np.cumsum(ds + 0.5 * base * dtheta)]) / right_per
    path = tmp_path / "ticks.csv"
    rows = ["t_s,ticks_left,ticks_right,true_x_m,true_y_m,true_theta_rad"]
    for t, a, b, truth in zip(log.t_s, left, right, log.truth, strict=True):
        rows.append(",".join(repr(float(v)) for v in (t, a, b, *truth)))
    path.write_text("\n".join(rows) + "\n")
    by_ticks = read_recording([path], robot, CSV)
    by_poses = read_recording([_write(tmp_path, log)], robot, CSV)
    assert len(by_ticks) == len(by_poses) == 4
    for a, b in zip(by_ticks, by_poses, strict=True):
        np.testing.assert_allclose(a.path.encoder_end_pose(), b.path.encoder_end_pose(), atol=1e-9)
        np.testing.assert_allclose(a.pose_change, b.pose_change, atol=1e-12)


@needs_optiodom
def test_joined_runs_written_as_a_log_csv_read_back_to_the_same_trials(tmp_path: Path) -> None:
    runs = sorted((OPTIODOM / "ivanjko").glob("*/*_run-0[1-3].csv"))
    path = tmp_path / "straight.csv"
    write_csv_log(path, joined_runs(runs))
    direct = read_recording(runs, optiodom_robot(), ImportOptions(format="optiodom"))
    from_csv = read_recording([path], optiodom_robot(), CSV)
    assert len(from_csv) == len(direct) == 12
    for a, b in zip(direct, from_csv, strict=True):
        np.testing.assert_array_equal(a.pose_change, b.pose_change)
        assert a.path.steps == b.path.steps


@needs_optiodom
@pytest.mark.parametrize("odometry", ["poses", "ticks"])
def test_optiodom_straight_runs_as_a_log_csv_read_back_to_the_same_trials(
    tmp_path: Path, odometry: str
) -> None:
    runs = sorted((OPTIODOM / "ivanjko").glob("*/*_run-0[1-3].csv"))
    robot = optiodom_robot()
    direct = read_recording(runs, robot, ImportOptions(format="optiodom"))
    assert len(direct) == 12
    recordings = [read_run(run) for run in runs]
    path = tmp_path / "straight.csv"
    offset = 0.0
    rows = []
    for number, rec in enumerate(recordings, start=1):
        counts = np.loadtxt(rec.source, delimiter=",")[:, 4:6].cumsum(axis=0)
        for i in range(len(rec.t_s)):
            odo = rec.odometry[i] if odometry == "poses" else counts[i, ::-1]  # left, right
            values = (rec.t_s[i] + offset, *odo, *rec.truth[i])
            rows.append(",".join(repr(float(v)) for v in values) + f",run{number}")
        offset += float(rec.t_s[-1]) + 0.05
    odo_columns = (
        "odo_x_m,odo_y_m,odo_theta_rad" if odometry == "poses" else "ticks_left,ticks_right"
    )
    header = f"t_s,{odo_columns},true_x_m,true_y_m,true_theta_rad,trial"
    path.write_text(header + "\n" + "\n".join(rows) + "\n")
    from_csv = read_recording([path], robot, CSV)
    assert len(from_csv) == len(direct)
    for a, b in zip(direct, from_csv, strict=True):
        assert (a.family, a.direction) == (b.family, b.direction) == ("straight", "forward")
        np.testing.assert_allclose(a.pose_change, b.pose_change, atol=1e-12)
        np.testing.assert_allclose(a.measurement_cov, b.measurement_cov, atol=1e-15)
        assert len(a.path.steps) == len(b.path.steps)
        np.testing.assert_allclose(a.path.encoder_end_pose(), b.path.encoder_end_pose(), atol=1e-9)


# bad input: each names the file, the line and the field


def _lines(tmp_path: Path, log: SynthLog) -> list[str]:
    return _write(tmp_path, log).read_text().splitlines()


def _rewrite(tmp_path: Path, lines: list[str]) -> Path:
    path = tmp_path / "bad.csv"
    path.write_text("\n".join(lines) + "\n")
    return path


def test_time_that_does_not_increase_names_the_line(tmp_path: Path) -> None:
    lines = _lines(tmp_path, synth_log(varied_motions()[:3]))
    lines[40] = lines[39]
    with pytest.raises(RecordingError, match=r"bad.csv line 41: t_s must increase"):
        read_recording([_rewrite(tmp_path, lines)], _robot(tmp_path), CSV)


def test_a_robot_never_at_rest_is_refused(tmp_path: Path) -> None:
    log = synth_log([Motion(10.0, v=0.1, w=0.3)])
    with pytest.raises(RecordingError, match=r"log.csv: odo_x_m.*never at rest.*--min-rest"):
        read_recording([_write(tmp_path, log)], _robot(tmp_path), CSV)


def test_a_log_that_only_rests_has_no_trial(tmp_path: Path) -> None:
    log = synth_log([rest(5.0)])
    with pytest.raises(
        RecordingError, match=r"log.csv line 2-\d+: no trial in the log: the odometry never moves"
    ):
        read_recording([_write(tmp_path, log)], _robot(tmp_path), CSV)


def test_a_robot_pushed_between_rests_is_no_trial(tmp_path: Path) -> None:
    log = synth_log([rest(2.0), rest(1.0), rest(2.0), Motion(5.0, v=0.2), rest(2.0)])
    # someone moves the robot 5 cm along the world x axis during 2-3 s: the wheels stay still
    push = np.clip(log.t_s - log.t_s[0] - 2.0, 0.0, 1.0) * 0.05
    log.truth[:, 0] += push
    trials = read_recording([_write(tmp_path, log)], _robot(tmp_path), CSV)
    assert len(trials) == 1
    assert trials[0].family == "straight"
    assert abs(trials[0].pose_change[0] - log.true_changes[0][0]) < 0.001


def test_a_gap_in_the_ground_truth_names_where_it_starts(tmp_path: Path) -> None:
    log = synth_log(varied_motions()[:3])
    lines = _lines(tmp_path, log)
    for index in range(200, 260):  # 1.2 s without capture, mid-run
        fields = lines[index].split(",")
        lines[index] = ",".join([*fields[:4], "", "", ""])
    with pytest.raises(
        RecordingError, match=r"line 200: true_x_m.*a gap in the ground truth of 1.2"
    ):
        read_recording([_rewrite(tmp_path, lines)], _robot(tmp_path), CSV)


def test_a_bad_value_names_the_line_and_the_column(tmp_path: Path) -> None:
    lines = _lines(tmp_path, synth_log(varied_motions()[:3]))
    fields = lines[9].split(",")
    fields[6] = "north"
    lines[9] = ",".join(fields)
    with pytest.raises(RecordingError, match=r"line 10: true_theta_rad: not a finite number"):
        read_recording([_rewrite(tmp_path, lines)], _robot(tmp_path), CSV)


@pytest.mark.parametrize(
    ("header", "message"),
    [
        ("t_s,odo_x_m,odo_y_m,odo_theta_rad,true_x_m,true_y_m", "true_theta_rad are missing"),
        ("t_s,odo_x_m,odo_y_m,true_x_m,true_y_m,true_theta_rad,x", "unknown column"),
        ("odo_x_m,odo_y_m,odo_theta_rad,true_x_m,true_y_m,true_theta_rad,trial", "t_s is missing"),
        ("t_s,ticks_left,odo_x_m,odo_y_m,odo_theta_rad,true_x_m,true_y_m,true_theta_rad", "either"),
    ],
)
def test_a_bad_header_names_what_is_wrong(tmp_path: Path, header: str, message: str) -> None:
    path = _rewrite(tmp_path, [header, "0,0,0,0,0,0,0"])
    with pytest.raises(RecordingError, match=rf"bad.csv line 1: .*{message}"):
        read_recording([path], _robot(tmp_path), CSV)


def test_a_trial_label_that_comes_back_is_refused(tmp_path: Path) -> None:
    log = synth_log(varied_motions()[:5])
    n = len(log.t_s)
    labels = ("a",) * (n // 3) + ("b",) * (n // 3) + ("a",) * (n - 2 * (n // 3))
    with pytest.raises(RecordingError, match=r"trial: trial 'a' appears again"):
        read_recording([_write(tmp_path, log, labels)], _robot(tmp_path), CSV)


def test_a_labelled_trial_whose_odometry_never_moves_is_refused(tmp_path: Path) -> None:
    log = synth_log([rest(3.0)])
    path = _write(tmp_path, log, ("x",) * len(log.t_s))
    with pytest.raises(RecordingError, match=r"line 2-\d+: odo_x_m.*trial 'x' never moves"):
        read_recording([path], _robot(tmp_path), CSV)


def test_a_log_without_any_labelled_row_has_no_trial(tmp_path: Path) -> None:
    log = synth_log(varied_motions()[:3])
    with pytest.raises(RecordingError, match=r"trial: no row names a trial"):
        read_recording([_write(tmp_path, log, ("",) * len(log.t_s))], _robot(tmp_path), CSV)


def test_not_a_regular_file_is_refused_before_reading(tmp_path: Path) -> None:
    with pytest.raises(RecordingError, match=r"is a directory: odohil reads only regular files"):
        read_recording([tmp_path], _robot(tmp_path), CSV)
    with pytest.raises(RecordingError, match=r"cannot read .*nothing.csv"):
        read_recording([tmp_path / "nothing.csv"], _robot(tmp_path), CSV)
