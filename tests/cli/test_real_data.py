"""Issue 20's acceptance on a real robot's recording (../shared/data/optiodom-june):
``estimate``, ``export`` and ``validate`` read the optiodom folders, an odohil
log CSV and general-path trial files through the one loader
(odohil/session/results/outcome.py), in process through the CLI.

The figures are the issue's outside fit: straight runs E_R -0.63 deg/m
[-0.85, -0.41], E_T -0.25 % [-0.28, -0.22]; circles: a turn-scale error of
about -1.2 % of the angle turned, different clockwise and counter-clockwise;
held out, the counter-clockwise circles' mean heading residual +2.49 deg
against a calibration on straight runs and clockwise circles.
"""

from __future__ import annotations

import json
import re
from dataclasses import replace
from functools import cache
from pathlib import Path
from typing import Any

import pytest
from typer.testing import CliRunner, Result

from odohil import units
from odohil.cli.app import app
from odohil.science.path_trials import PathTrial
from odohil.session.trials.logs import ImportOptions, read_recording
from odohil.session.trials.logs.csv_log import write_csv_log
from odohil.session.trials.logs.optiodom import joined_runs
from odohil.session.trials.path_trial_file import write_path_trials
from tests.logs.data import OPTIODOM, OPTIODOM_ROBOT, needs_optiodom, optiodom_robot

pytestmark = needs_optiodom

E_R_INTERVAL = (-0.85, -0.41)
"""deg/m, the issue's straight-run interval."""
E_T_INTERVAL = (-0.0028, -0.0022)
"""The issue's straight-run interval (-0.28 % to -0.22 %)."""


def invoke(*args: str | Path) -> Result:
    return CliRunner().invoke(app, [str(a) for a in args])


@cache
def _kind(kind: str) -> tuple[PathTrial, ...]:
    options = ImportOptions(format="optiodom")
    return tuple(read_recording([OPTIODOM / kind], optiodom_robot(), options))


def _exact_robot(tmp_path: Path) -> Path:
    """The optiodom robot with its turns declared exact (the four-parameter model)."""
    text = OPTIODOM_ROBOT.read_text(encoding="utf-8")
    assert "turns_exact = false" in text
    robot = tmp_path / "optiodom-exact.toml"
    robot.write_text(text.replace("turns_exact = false", "turns_exact = true"), encoding="utf-8")
    return robot


def _trial_file(path: Path, trials: list[PathTrial]) -> Path:
    write_path_trials(path, [replace(t, trial=i + 1) for i, t in enumerate(trials)], "optiodom")
    return path


def _paper(data: dict[str, Any], name: str) -> tuple[float, float, float]:
    p = data["parameters"][name]
    low, high = p["ci95"]
    return tuple(units.parameter_to_paper(name, v) for v in (p["value"], low, high))  # type: ignore[return-value]


def _check_straight(result: Result) -> None:
    assert result.exit_code == 0, result.output
    data = json.loads(result.stdout)
    assert data["verdict"]["status"] == "trusted", data["verdict"]
    assert data["n_trials"] == 14
    e_r = _paper(data, "E_R")[0]
    e_t = data["parameters"]["E_T"]["value"]
    assert E_R_INTERVAL[0] < e_r < E_R_INTERVAL[1], e_r
    assert E_T_INTERVAL[0] < e_t < E_T_INTERVAL[1], e_t


def test_estimate_june_straight_runs_from_the_optiodom_folder() -> None:
    # the folder holds straight runs and spins: --family straight keeps the runs
    _check_straight(
        invoke(
            "estimate",
            OPTIODOM / "ivanjko",
            "--robot",
            OPTIODOM_ROBOT,
            "--family",
            "straight",
            "--json",
        )
    )


def test_estimate_june_straight_runs_from_an_odohil_log_csv(tmp_path: Path) -> None:
    runs = sorted({Path(t.source) for t in _kind("ivanjko") if t.family == "straight"})
    assert len(runs) == 14
    log = tmp_path / "straight.csv"
    write_csv_log(log, joined_runs(runs))
    _check_straight(invoke("estimate", log, "--robot", OPTIODOM_ROBOT, "--json"))


def test_june_circles_with_exact_turns_are_not_trusted_and_the_reason_names_the_direction(
    tmp_path: Path,
) -> None:
    result = invoke("estimate", OPTIODOM / "circular", "--robot", _exact_robot(tmp_path), "--json")
    assert result.exit_code == 3, result.output
    data = json.loads(result.stdout)
    assert data["verdict"]["status"] != "trusted"
    reasons = " ".join(data["verdict"]["reasons"])
    assert re.search(r"heading residual [+-][\d.]+ deg on the \d+ (cw|ccw) arc trials", reasons), (
        reasons
    )
    assert "e_turn" not in data["parameters"]


def test_june_circles_with_turn_errors_report_e_turn_excluding_zero() -> None:
    result = invoke("estimate", OPTIODOM / "circular", "--robot", OPTIODOM_ROBOT, "--json")
    assert result.exit_code == 0, result.output
    data = json.loads(result.stdout)
    assert data["verdict"]["status"] == "trusted"
    # the data ask for one turn scale per direction; the clockwise one excludes 0
    names = [n for n in data["parameters"] if n.startswith("e_turn")]
    assert names == ["e_turn_ccw", "e_turn_cw"], names
    value, low, high = _paper(data, "e_turn_cw")
    assert low <= value <= high < 0


def test_export_carries_the_turn_errors_and_says_where_no_key_takes_them() -> None:
    args = ("export", OPTIODOM / "circular", "--robot", OPTIODOM_ROBOT)
    refused = invoke(*args, "--format", "json")
    # per direction, E_R and the turn scales share the circles' one radius: too
    # imprecise a correction to export without --force
    assert refused.exit_code == 3, refused.output
    assert "not told from none" in " ".join(refused.output.split())
    forced = invoke(*args, "--format", "json", "--force")
    assert forced.exit_code == 0, forced.output
    doc = json.loads(forced.stdout)
    assert set(doc["turn_errors"]) == {"e_turn_ccw", "e_turn_cw"}
    assert doc["parameter_covariance"]["order"][4:] == ["e_turn_ccw", "e_turn_cw"]
    yaml = invoke(*args, "--format", "ros2-diff-drive", "--force")
    assert yaml.exit_code == 0, yaml.output
    assert "Turn errors (turns_exact = false; no key here takes them" in yaml.stdout


def test_validate_straight_and_cw_circles_against_ccw_circles_finds_the_heading_bias(
    tmp_path: Path,
) -> None:
    """Calibrated (with e_turn) on the straight runs and the clockwise circles,
    the fit does NOT predict the counter-clockwise circles: a remaining bias is
    found (the issue's +2.49 deg), by the mean-residual test, while the spread
    (NEES) tests alone pass."""
    straight = [t for t in _kind("ivanjko") if t.family == "straight"]
    cw = [t for t in _kind("circular") if t.direction == "cw"]
    ccw = [t for t in _kind("circular") if t.direction == "ccw"]
    assert (len(straight), len(cw), len(ccw)) == (14, 16, 16)
    cal = _trial_file(tmp_path / "cal.jsonl", straight + cw)
    held = _trial_file(tmp_path / "held.jsonl", ccw)
    result = invoke("validate", cal, "--path", f"file:{held}", "--robot", OPTIODOM_ROBOT, "--json")
    assert result.exit_code == 3, result.output
    data = json.loads(result.stdout)
    verdict = data["verdict"]
    assert "e_turn" in data["calibration"]["parameters"]
    assert data["calibration"]["verdict"]["status"] == "trusted"
    assert "bias theta" in verdict["failed"]
    assert not {"overall", "x", "y", "theta"} & set(verdict["failed"])  # NEES blind to it
    heading = verdict["bias"]["axes"]["theta"]
    assert not heading["passed"]
    assert units.radians_to_degrees(heading["mean"][0]) == pytest.approx(2.49, abs=0.5)


def test_validate_cw_circles_against_ccw_circles_finds_a_bias_short_of_the_level(
    tmp_path: Path,
) -> None:
    """Calibrated on the clockwise circles alone (E_R and e_turn share their one
    radius, so the fit's uncertainty is wide), the counter-clockwise circles
    show a bias: the joint mean-residual statistic is 16.3 on 3 degrees of
    freedom. Until stop 36 its threshold was chi-square's 15.8 (level 0.00125,
    the 0.01 split over the eight tests) and it failed the validation, p about
    0.001. Since issue 31's fix the threshold holds the calibration's own
    uncertainty (its covariance is an estimate with few degrees of freedom:
    F(3, nu_W), 20.5 here, docs/validation.md), and the same bias has p 0.004:
    evidence, short of the validation's level. The validation says so with
    its numbers; the estimate's misfit check distrusts the circles by direction
    (tests/estimation/test_misfit_optiodom.py)."""
    cal = _trial_file(tmp_path / "cw.jsonl", [t for t in _kind("circular") if t.direction == "cw"])
    held = _trial_file(
        tmp_path / "ccw.jsonl", [t for t in _kind("circular") if t.direction == "ccw"]
    )
    result = invoke("validate", cal, "--path", f"file:{held}", "--robot", OPTIODOM_ROBOT, "--json")
    assert result.exit_code == 0, result.output
    bias = json.loads(result.stdout)["verdict"]["bias"]["overall"]
    assert bias["statistic"] > 15.0, bias  # chi-square(3)'s 0.00125 point is 15.8
    assert 0.00125 < bias["p_value"] < 0.01, bias
    assert bias["threshold"] > bias["statistic"], bias


def test_validate_a_recording_calibration_needs_the_robot(tmp_path: Path) -> None:
    held = _trial_file(tmp_path / "held.jsonl", list(_kind("circular"))[:4])
    result = invoke("validate", OPTIODOM / "circular", "--path", f"file:{held}")
    assert result.exit_code == 2, result.output
    assert "--robot" in result.output


def test_a_recording_without_robot_or_with_an_empty_selection_is_refused() -> None:
    no_robot = invoke("estimate", OPTIODOM / "ivanjko")
    assert no_robot.exit_code == 2, no_robot.output
    assert "--robot is needed" in no_robot.output
    empty = invoke(
        "estimate", OPTIODOM / "circular", "--robot", OPTIODOM_ROBOT, "--family", "straight"
    )
    assert empty.exit_code == 2, empty.output
    assert "--family straight" in " ".join(empty.output.split())
    paper = invoke(
        "estimate", OPTIODOM / "circular", "--robot", OPTIODOM_ROBOT, "--method", "paper"
    )
    assert paper.exit_code == 2, paper.output
    assert "--method paper" in " ".join(paper.output.split())


def test_report_of_the_straight_runs_and_refusal_of_the_exact_turn_circles(
    tmp_path: Path,
) -> None:
    out = tmp_path / "straight"
    result = invoke(
        "report",
        OPTIODOM / "ivanjko",
        "--family",
        "straight",
        "--robot",
        OPTIODOM_ROBOT,
        "--out",
        out,
    )
    assert result.exit_code == 0, result.output
    data = json.loads((out / "parameters.json").read_text(encoding="utf-8"))
    assert data["verdict"]["status"] == "trusted"
    assert data["general_paths"][0]["family"] == "straight"
    page = (out / "index.html").read_text(encoding="utf-8")
    assert "Mean residuals by path family and direction" in page
    assert "ros2_diff_drive.yaml" in page
    refused = tmp_path / "circles"
    result = invoke(
        "report", OPTIODOM / "circular", "--robot", _exact_robot(tmp_path), "--out", refused
    )
    assert result.exit_code == 3, result.output
    assert not refused.exists()


def test_direction_selection_keeps_one_direction() -> None:
    result = invoke(
        "estimate", OPTIODOM / "circular", "--direction", "cw", "--robot", OPTIODOM_ROBOT, "--json"
    )
    assert result.exit_code == 0, result.output  # cw circles alone: trusted
    data = json.loads(result.stdout)
    assert [(g["family"], g["direction"], g["trials"]) for g in data["general_paths"]] == [
        ("arc", "cw", 16)
    ]
