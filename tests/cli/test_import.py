"""``odohil import``: a recording in, a general-path trial file out; exit 0
with a summary, exit 2 naming the file, line and field on bad input."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner, Result

from odohil.cli.app import app
from odohil.session.trials.logs.csv_log import write_csv_log
from odohil.session.trials.logs.recording import Recording
from odohil.session.trials.path_trial_file import read_path_trials
from tests.logs.data import OPTIODOM, OPTIODOM_ROBOT, needs_optiodom
from tests.logs.synth import Motion, synth_log, varied_motions


def invoke(*args: str | Path) -> Result:
    return CliRunner().invoke(app, [str(a) for a in args])


def flat(result: Result) -> str:
    text = result.output
    for mark in "│╭╮╰╯─┃━┏┓┗┛┡┩\n":
        text = text.replace(mark, " ")
    return " ".join(text.split())


def _log(tmp_path: Path, motions: list[Motion]) -> Path:
    log = synth_log(motions)
    path = tmp_path / "log.csv"
    lines = np.arange(2, 2 + len(log.t_s))
    write_csv_log(path, Recording("s", log.t_s, log.odometry, log.truth, lines))
    return path


def test_a_csv_log_becomes_a_trial_file_with_a_summary(tmp_path: Path) -> None:
    out = tmp_path / "trials.jsonl"
    result = invoke("import", _log(tmp_path, varied_motions()), "--robot", "create2", "--out", out)
    assert result.exit_code == 0, result.output
    text = flat(result)
    assert "4 trials from 1 log path, read as csv" in text
    assert "straight forward 1 1.000" in text
    assert "spin cw 1" in text
    assert "straight backward 1 0.450" in text
    assert "arc ccw 1 1.59" in text  # chords of a 1.6 m arc (odohil/science/odometry_paths.py)
    assert "wrote 4 trials" in text
    trials = read_path_trials(out)
    assert [t.family for t in trials] == ["straight", "spin", "straight", "arc"]


@needs_optiodom
def test_the_optiodom_folders_as_given(tmp_path: Path) -> None:
    out = tmp_path / "ivanjko.jsonl"
    result = invoke(
        "import",
        OPTIODOM / "ivanjko",
        "--robot",
        OPTIODOM_ROBOT,
        "--out",
        out,
        "--format",
        "optiodom",
    )
    assert result.exit_code == 0, result.output
    # 20.965 m: each run's path spans its rests' still parts (the creep inside a
    # rest is driven; odohil/session/trials/logs/recording.py)
    assert "straight forward 14 20.965" in flat(result)
    assert len(read_path_trials(out)) == 42


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--min-rest", "-1"], "--min-rest must be a positive number of seconds"),
        (["--time-offset", "nan"], "--time-offset must be a finite number"),
        (["--format", "tum"], "TUM files come in pairs"),
    ],
)
def test_bad_options_exit_2_naming_the_option(
    tmp_path: Path, args: list[str], message: str
) -> None:
    out = tmp_path / "trials.jsonl"
    log = _log(tmp_path, varied_motions())
    result = invoke("import", log, "--robot", "create2", "--out", out, *args)
    assert result.exit_code == 2, result.output
    assert message in flat(result)
    assert not out.exists()


def test_a_log_never_at_rest_exits_2_and_writes_nothing(tmp_path: Path) -> None:
    out = tmp_path / "trials.jsonl"
    log = _log(tmp_path, [Motion(10.0, v=0.1, w=0.2)])
    result = invoke("import", log, "--robot", "create2", "--out", out)
    assert result.exit_code == 2
    text = flat(result)
    # rich wraps a long path mid-word: compare without white space
    assert "log.csv:odo_x_m/odo_y_m/odo_theta_rad,true_x_m/true_y_m/true_theta_rad:" in "".join(
        text.split()
    )
    assert "the robot is never at rest" in text
    assert not out.exists()


def test_a_missing_log_and_an_unknown_robot_exit_2(tmp_path: Path) -> None:
    out = tmp_path / "trials.jsonl"
    result = invoke("import", tmp_path / "none.csv", "--robot", "create2", "--out", out)
    assert result.exit_code == 2
    assert "cannot read" in flat(result)
    assert "none.csv" in "".join(flat(result).split())
    result = invoke("import", tmp_path / "none.csv", "--robot", "nosuchrobot", "--out", out)
    assert result.exit_code == 2
    assert "--robot" in flat(result)
