"""``odohil plan`` with general paths (issue 19, deliverable 3): ``--evaluate``
scores a plan naming paths (the turn errors with the four when the robot's
turns carry error, and what it cannot estimate with the reason), and
``--compare-paths`` says what squares or circles buy over the best
forth-and-back plan of the same operator time. In process through typer's runner."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from typer.testing import CliRunner, Result

from odohil.cli.app import app
from odohil.cli.exit_codes import EXIT_BAD_INPUT, EXIT_OK
from odohil.robots import __file__ as robots_init
from odohil.science.path_designs import parse_path_design
from odohil.science.path_plans import RobotModel, Shape, score_plan
from odohil.science.paths import Design
from odohil.session.commands.plan_paths import (
    PathComparisonRequest,
    compare_paths,
    comparison_document,
)
from odohil.session.robots.description import load_robot_description

CREATE2 = Path(robots_init).parent / "create2.toml"
PLAN = "path=square:1,cw,n=10;k=1,l=2,n=10"


def plan(*args: str) -> Result:
    return CliRunner().invoke(app, ["plan", *args], env={"COLUMNS": "200", "NO_COLOR": "1"})


def test_evaluate_scores_a_plan_naming_a_path_with_the_turn_errors() -> None:
    result = plan("--evaluate", PLAN, "--robot", "create2", "--json")
    assert result.exit_code == EXIT_OK, result.output
    document = json.loads(result.stdout)
    parameters = document["parameters"]
    assert list(parameters) == ["E_R", "E_T", "K_theta", "K_rho", "e_turn_spin", "e_turn_arc",
                                "K_spin"]  # fmt: skip
    robot = RobotModel.of(load_robot_description(CREATE2))
    items: list[tuple[Shape, int]] = [
        (parse_path_design("square:1,cw"), 10),
        (Design(1.0, 2.0, "reverse"), 10),
    ]
    expected = score_plan(items, robot)
    for entry in expected.parameters:
        shown = parameters[entry.name]
        assert shown["estimable"] is entry.estimable, entry.name
        if entry.estimable:
            assert shown["stderr_si"] == pytest.approx(entry.standard_error, rel=1e-9)
        else:
            assert shown["stderr_si"] is None
            assert shown["reason"] == entry.reason
    assert parameters["e_turn_arc"]["estimable"] is False
    assert "makes no arcs" in parameters["e_turn_arc"]["reason"]
    assert document["n_trials"] == 20
    assert document["operator_minutes"] > 20 * 2  # 120 s a trial to mark and measure


def test_evaluate_prints_a_plan_naming_a_path_for_people() -> None:
    result = plan("--evaluate", PLAN, "--robot", "create2")
    assert result.exit_code == EXIT_OK, result.output
    text = " ".join(result.stdout.split())
    assert "square 1 m cw" in text
    assert "e_turn_spin" in text
    assert "Cannot estimate e_turn_arc: the plan makes no arcs" in text


def test_a_robot_whose_turns_are_exact_scores_the_four_only() -> None:
    result = plan("--evaluate", "path=square:2,n=12;path=square:2,cw,n=12", "--json")
    assert result.exit_code == EXIT_OK, result.output
    assert list(json.loads(result.stdout)["parameters"]) == ["E_R", "E_T", "K_theta", "K_rho"]


def test_compare_paths_gives_the_comparison_document() -> None:
    result = plan("--compare-paths", "square:1,cw;square:1,ccw", "--budget-min", "120",
                  "--robot", "create2", "--split-directions", "--json")  # fmt: skip
    assert result.exit_code == EXIT_OK, result.output
    found = compare_paths(
        PathComparisonRequest(
            "square:1,cw;square:1,ccw", 120.0, robot=CREATE2, split_directions=True
        )
    )
    assert json.loads(result.stdout) == json.loads(json.dumps(comparison_document(found)))
    assert "e_turn_spin_cw" in json.loads(result.stdout)["buys"]


def test_compare_paths_prints_the_findings_and_the_three_plans() -> None:
    result = plan("--compare-paths", "square:1,cw;square:1,ccw", "--budget-min", "120",
                  "--robot", "create2")  # fmt: skip
    assert result.exit_code == EXIT_OK, result.output
    text = " ".join(result.stdout.split())
    for title in ("Best turn-free forth-and-back:", "Best forth-and-back with turns:",
                  "Best with the general paths:"):  # fmt: skip
        assert title in text
    assert "over the best forth-and-back plan of 120 min" in text
    assert "e_turn_spin:" in text


@pytest.mark.parametrize(
    ("args", "said"),
    [
        (("--evaluate", PLAN, "--budget-min", "60"), "give no --budget-m/--budget-min"),
        (("--evaluate", "path=triangle:1,n=10"), "unknown path"),
        (("--compare-paths", "square:1"), "--compare-paths needs --budget-min"),
        (("--compare-paths", "square:1", "--budget-min", "60", "--evaluate", PLAN), "not both"),
        (("--compare-paths", "triangle:1", "--budget-min", "60"), "unknown path"),
        (("--compare-paths", "square:1", "--budget-min", "60", "--budget-m", "100"), "--budget-m"),
    ],
)
def test_bad_input_exits_2_naming_the_option(args: tuple[str, ...], said: str) -> None:
    result = plan(*args)
    assert result.exit_code == EXIT_BAD_INPUT
    assert said in " ".join(result.output.replace("│", " ").split())
