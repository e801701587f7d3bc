"""The optiodom data set's June folders read as given (../shared/data/optiodom-june)."""

from __future__ import annotations

import collections
import shutil
from pathlib import Path

import numpy as np
import pytest

from odohil.errors import RecordingError
from odohil.science.odometry_paths import odometry_end_pose
from odohil.session.trials.logs import ImportOptions, read_recording
from odohil.session.trials.logs.optiodom import read_run
from tests.logs.data import OPTIODOM, needs_optiodom, optiodom_robot

pytestmark = needs_optiodom
OPTIONS = ImportOptions(format="optiodom")


def _families(trials: list) -> collections.Counter[tuple[str, str]]:
    return collections.Counter((t.family, t.direction) for t in trials)


def test_ivanjko_gives_14_straight_runs_of_1_5_m_and_28_spins() -> None:
    trials = read_recording([OPTIODOM / "ivanjko"], optiodom_robot(), OPTIONS)
    # the README: 42 runs, straight runs of 1.5 m and in-place 180 degree turns
    assert len(trials) == 42
    assert _families(trials) == {
        ("straight", "forward"): 14,
        ("spin", "cw"): 14,
        ("spin", "ccw"): 14,
    }
    straight = [t for t in trials if t.family == "straight"]
    for trial in straight:
        assert 1.47 < trial.path.distance_m < 1.51
        assert 1.47 < trial.pose_change[0] < 1.51  # measured by the ground truth
        assert abs(trial.pose_change[1]) < 0.15
    spins = [t for t in trials if t.family == "spin"]
    for trial in spins:
        assert abs(abs(trial.path.net_turn_rad) - np.pi) < 0.25
        assert all(
            getattr(step, "kind", "spin") == "spin"
            for step in trial.path.steps
            if abs(getattr(step, "angle_rad", 0.0)) > 0.5
        )
    assert [t.trial for t in trials] == list(range(1, 43))
    assert trials[0].source.endswith("250620201618_run-01.csv")


def test_circles_give_cw_and_ccw_arcs_of_a_few_dozen_legs() -> None:
    trials = read_recording([OPTIODOM / "circular"], optiodom_robot(), OPTIONS)
    assert len(trials) == 32
    assert _families(trials) == {("arc", "cw"): 16, ("arc", "ccw"): 16}
    two_laps = [t for t in trials if abs(abs(t.path.net_turn_rad) - 4 * np.pi) < 0.5]
    assert len(two_laps) >= 20
    for trial in two_laps:
        assert 30 <= len(trial.path.legs.length_m) <= 60
        # the heading residual of a circle is what the issue reports: about +9
        # degrees clockwise, -9 counter-clockwise (a turn-scale error)
        residual = np.degrees(trial.pose_change[2] - trial.path.encoder_end_pose()[2])
        assert 3.0 < residual * (1 if trial.direction == "cw" else -1) < 15.0


def test_every_compressed_path_ends_where_its_odometry_ends() -> None:
    """On the real runs: the legs and turns end where the counts, integrated
    sample by sample, end (1e-9 m, 1e-12 rad; odohil/science/odometry_paths.py)."""
    trials = read_recording([OPTIODOM], optiodom_robot(), OPTIONS)
    assert len(trials) == 42 + 32 + 28
    for trial in trials:
        assert trial.span_s is not None
        run = read_run(Path(trial.source))
        first, last = np.searchsorted(run.t_s, trial.span_s)
        odometry = run.odometry[first : last + 1]
        x, y, theta = trial.path.encoder_end_pose()
        ox, oy, otheta = odometry_end_pose(odometry)
        assert abs(x - ox) < 1e-9
        assert abs(y - oy) < 1e-9
        assert abs(theta - otheta) < 1e-12
        assert len(trial.path.legs.length_m) <= 70


def test_squares_are_mixed_paths_of_both_senses() -> None:
    trials = read_recording([OPTIODOM / "square"], optiodom_robot(), OPTIONS)
    assert _families(trials) == {("mixed", "cw"): 14, ("mixed", "ccw"): 14}
    for trial in trials:
        assert 2.9 < trial.path.distance_m < 3.05  # four sides of 0.75 m


def test_a_run_file_alone_reads_as_one_trial() -> None:
    run = OPTIODOM / "ivanjko/250620201618/250620201618_run-01.csv"
    (trial,) = read_recording([run], optiodom_robot(), ImportOptions())  # format guessed
    assert trial.family == "straight"
    assert trial.span_s is not None
    assert 0.0 < trial.span_s[0] < 2.0 < 30.0 < trial.span_s[1] < 33.3


def _copy_session(tmp_path: Path) -> Path:
    session = tmp_path / "250620201618"
    shutil.copytree(OPTIODOM / "ivanjko/250620201618", session)
    return session


def test_metadata_that_disagree_with_the_runs_are_refused(tmp_path: Path) -> None:
    session = _copy_session(tmp_path)
    (session / "250620201618_run-09.csv").unlink()
    with pytest.raises(RecordingError, match=r"_metadata.csv: N: .* 9 runs.* 8 run files"):
        read_recording([session], optiodom_robot(), OPTIONS)


def test_a_bad_row_names_the_line_and_the_column(tmp_path: Path) -> None:
    session = _copy_session(tmp_path)
    run = session / "250620201618_run-02.csv"
    lines = run.read_text().splitlines()
    lines[6] = lines[6].rsplit(",", 1)[0] + ",x"
    run.write_text("\n".join(lines) + "\n")
    with pytest.raises(RecordingError, match=r"run-02.csv line 7: left_counts: not a finite"):
        read_recording([session], optiodom_robot(), OPTIONS)


def test_time_that_goes_back_is_refused(tmp_path: Path) -> None:
    session = _copy_session(tmp_path)
    run = session / "250620201618_run-03.csv"
    lines = run.read_text().splitlines()
    lines[10], lines[11] = lines[11], lines[10]
    run.write_text("\n".join(lines) + "\n")
    with pytest.raises(RecordingError, match=r"run-03.csv line 12: t_s must increase"):
        read_recording([session], optiodom_robot(), OPTIONS)


def test_a_run_that_starts_moving_starts_at_its_first_sample(tmp_path: Path) -> None:
    session = _copy_session(tmp_path)
    run = session / "250620201618_run-01.csv"
    whole = read_recording([session], optiodom_robot(), OPTIONS)[0]
    lines = run.read_text().splitlines()
    del lines[:13]  # the rest before the motion (refused before issue 30)
    run.write_text("\n".join(lines) + "\n")
    cut = read_recording([session], optiodom_robot(), OPTIONS)[0]
    assert cut.span_s is not None
    assert cut.span_s[0] == float(lines[0].split(",")[0])
    assert cut.family == whole.family == "straight"
    assert abs(cut.path.distance_m - whole.path.distance_m) < 0.01
    assert abs(cut.pose_change[0] - whole.pose_change[0]) < 0.01
