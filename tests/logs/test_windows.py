"""Continuous logs cut into windows of travelled wheel distance, ``--window-m``
(issue 30, part 2): a log without rests or a trial column, refused before
(``the robot is never at rest ... so no trial can be cut``), gives windows as
general-path trials whose estimate holds the simulator's truth; a gap in the
ground truth leaves its window out, counted; the last partial window is
dropped; a bad ``--window-m`` exits 2 on every command that reads a recording."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner, Result

from odohil.cli.app import app
from odohil.cli.exit_codes import EXIT_BAD_INPUT, EXIT_OK
from odohil.errors import ParameterError
from odohil.science.distance_windows import distance_windows
from odohil.session.trials.path_trial_file import read_path_trials
from tests.logs.continuous import TRUE, continuous_log, write_description

WINDOW = "2"


def odohil(*args: str | Path) -> Result:
    return CliRunner().invoke(app, [str(a) for a in args], env={"COLUMNS": "200"})


GAP_WINDOW = 10
"""The window (0-based) in whose middle gap.csv misses 1.5 s of ground truth."""


@pytest.fixture(scope="module")
def lab(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A 60 m continuous log (log.csv), its robot (robot.toml), and the same
    log with 1.5 s of ground truth missing inside one window (gap.csv)."""
    folder = tmp_path_factory.mktemp("lab")
    log = continuous_log(folder / "log.csv", seed=1)
    first, last = distance_windows(log.odometry, 2.0).spans[GAP_WINDOW]
    middle = 0.5 * float(log.t_s[first] + log.t_s[last])
    continuous_log(folder / "gap.csv", seed=1, truth_gap_s=(middle - 0.75, middle + 0.75))
    write_description(folder)
    return folder


def test_a_continuous_log_is_refused_without_windows(lab: Path) -> None:
    done = odohil("estimate", lab / "log.csv", "--robot", lab / "robot.toml")
    assert done.exit_code == EXIT_BAD_INPUT
    assert "never at rest" in done.output


def test_windows_estimate_holds_the_simulators_truth(lab: Path) -> None:
    done = odohil(
        "estimate", lab / "log.csv", "--robot", lab / "robot.toml", "--window-m", WINDOW, "--json"
    )
    assert done.exit_code == EXIT_OK, done.output
    data = json.loads(done.output)
    assert data["verdict"]["status"] == "trusted"
    for name in ("E_R", "E_T", "K_theta", "K_rho"):
        low, high = data["parameters"][name]["ci95"]
        assert low <= getattr(TRUE, name.lower()) <= high, name
    windows = data["windows"]
    assert windows["window_m"] == 2.0
    assert windows["windows"] == data["n_trials"] == 29  # 60.4 m: 29 whole windows
    assert windows["left_out_truth_gap"] == 0
    assert windows["partial_dropped"] == 1
    assert 0 < windows["partial_dropped_m"] < 2.0
    assert data["general_paths"] == [
        {
            "family": "window",
            "direction": "mixed",
            "trials": 29,
            "distance_m": pytest.approx(58, abs=0.5),
        }
    ]


def test_a_truth_gap_leaves_its_window_out_counted(lab: Path) -> None:
    rows = np.loadtxt(lab / "gap.csv", delimiter=",", skiprows=1, usecols=(1, 2, 3))
    spans = distance_windows(rows, 2.0).spans  # cut by the odometry alone: as log.csv's
    args = ("estimate", lab / "gap.csv", "--robot", lab / "robot.toml", "--window-m", WINDOW)
    data = json.loads(odohil(*args, "--json").output)
    assert data["windows"]["left_out_truth_gap"] == 1
    assert data["windows"]["windows"] == data["n_trials"] == len(spans) - 1 == 28
    assert "a gap in the ground truth of 1.6 s" in data["windows"]["left_out"][0]
    text = odohil(*args).output
    assert (
        "windows of 2 m travelled (--window-m): 28 trials, 1 left out for a gap in the ground truth"
        in text
    )


def test_the_last_partial_window_is_dropped() -> None:
    x = np.arange(0.0, 5.5 + 1e-9, 0.01)  # 5.5 m straight, 1 cm a sample
    odometry = np.stack([x, np.zeros_like(x), np.zeros_like(x)], axis=1)
    windows = distance_windows(odometry, 2.0)
    assert windows.spans == ((0, 200), (201, 401))  # no shared sample
    assert windows.travelled_m == pytest.approx(5.5)
    assert windows.dropped_m == pytest.approx(5.5 - 4.01)
    turning = odometry.copy()
    turning[:, 2] = np.linspace(0, 20, len(x))  # turns travel nothing of their own
    assert distance_windows(turning, 2.0).spans == windows.spans


@pytest.mark.parametrize("bad", ["0", "-1", "nan", "inf"])
def test_a_bad_window_exits_2_naming_the_option(lab: Path, bad: str) -> None:
    done = odohil("estimate", lab / "log.csv", "--robot", lab / "robot.toml", "--window-m", bad)
    assert done.exit_code == EXIT_BAD_INPUT
    assert "--window-m must be a finite number of metres above 0 (0 < --window-m < inf)" in (
        done.output
    )
    with pytest.raises(ParameterError, match="above 0"):
        distance_windows(np.zeros((3, 3)), float(bad))


REQUIRED = {
    "import": ("--out", "t.jsonl"),
    "estimate": (),
    "export": ("--format", "json"),
    "report": ("--out", "r.html"),
    "validate": ("--path", "square:1"),
}
"""What else each command that reads a recording requires."""


@pytest.mark.parametrize("command", sorted(REQUIRED))
def test_every_command_reading_a_recording_takes_window_m(lab: Path, command: str) -> None:
    source = (lab / "log.csv", "--robot", lab / "robot.toml", *REQUIRED[command])
    done = odohil(command, *source, "--window-m", "0")
    assert done.exit_code == EXIT_BAD_INPUT, done.output
    assert "--window-m must be a finite number" in done.output


def test_shorter_than_one_window_says_so(lab: Path) -> None:
    done = odohil("estimate", lab / "log.csv", "--robot", lab / "robot.toml", "--window-m", "100")
    assert done.exit_code == EXIT_BAD_INPUT
    assert "travels 60.110 m in all, shorter than one window of --window-m 100 m" in done.output


def test_windows_need_pose_sigma(lab: Path, tmp_path: Path) -> None:
    robot = write_description(tmp_path, pose_sigma=False)
    done = odohil("estimate", lab / "log.csv", "--robot", robot, "--window-m", WINDOW)
    assert done.exit_code == EXIT_BAD_INPUT
    assert "--window-m: the robot description gives no [measurement] pose_sigma" in done.output


def test_import_writes_the_windows_and_counts_them(lab: Path, tmp_path: Path) -> None:
    out = tmp_path / "trials.jsonl"
    args = ("import", lab / "gap.csv", "--robot", lab / "robot.toml", "--out", out)
    done = odohil(*args, "--window-m", WINDOW)
    assert done.exit_code == EXIT_OK, done.output
    assert "wrote 28 trials" in done.output
    assert "28 trials, 1 left out for a gap in the ground truth, 1 partial window dropped" in (
        done.output
    )
    assert [t.family for t in read_path_trials(out)] == ["window"] * 28


def test_the_report_page_counts_the_windows_left_out(lab: Path, tmp_path: Path) -> None:
    # issue 30: the text and --json counted the windows; the report page did not
    out = tmp_path / "report"
    args = ("report", lab / "gap.csv", "--robot", lab / "robot.toml", "--window-m", WINDOW)
    done = odohil(*args, "--out", out)
    assert done.exit_code == EXIT_OK, done.output
    page = " ".join((out / "index.html").read_text(encoding="utf-8").split())
    assert (
        "windows of 2 m travelled (--window-m): 28 trials, 1 left out for a gap in the ground truth"
        in page
    )
    assert "a gap in the ground truth of 1.6 s" in page  # where and why


def test_validate_counts_the_held_out_windows_left_out(lab: Path) -> None:
    # issue 30: validate on a held-out continuous log said only "28 trials of file:..."
    args = ("validate", lab / "log.csv", "--robot", lab / "robot.toml", "--window-m", WINDOW)
    done = odohil(*args, "--path", f"file:{lab / 'gap.csv'}")
    assert done.exit_code == EXIT_OK, done.output
    text = " ".join(done.output.split())
    assert "28 trials of file:" in text
    assert (
        "held-out windows of 2 m travelled (--window-m): 28 trials, 1 left out for a gap in the "
        "ground truth" in text
    )
    data = json.loads(odohil(*args, "--path", f"file:{lab / 'gap.csv'}", "--json").stdout)
    assert data["windows"]["left_out_truth_gap"] == 1
    assert data["windows"]["windows"] == data["n_trials"] == 28
