"""``odohil plan``, run as the real console command."""

from __future__ import annotations

import json
import math
import os
import shutil
import subprocess
from pathlib import Path

import pytest

from odohil.science.fisher import default_description
from odohil.science.parameters import NOMAD150, PARAMETER_NAMES
from odohil.science.paths import Design
from odohil.science.planner import expected_standard_errors
from odohil.session.robots.description import load_robot_description
from tests import forked

ODOHIL = shutil.which("odohil") or "odohil"

ROBOT_TOML = """
[screws]
A = [0.15, 0.0]
B = [-0.075, 0.13]
C = [-0.075, -0.13]
[measurement]
sigma_m = 0.002
cross = [["A", "B"], ["B", "C"]]
"""


def run(*args: str) -> subprocess.CompletedProcess[str]:
    # a process of its own, forked from a server that imported odohil once (tests/forked.py)
    env = {**os.environ, "COLUMNS": "160", "NO_COLOR": "1"}
    return forked.completed([ODOHIL, "plan", *args], 300, env)


def _designs(document: dict[str, object]) -> list[tuple[Design, int]]:
    rows = document["designs"]
    assert isinstance(rows, list)
    return [(Design(r["k"], r["l_m"], r["variant"]), r["n_trials"]) for r in rows]


def test_json_plan_with_paper_targets() -> None:
    result = run(
        "--budget-m", "600", "--max-trials", "40", "--max-designs", "1",
        "--target-E-R", "0.004", "--target-K-theta", "0.003",
        "--target-E-T", "0.04", "--target-K-rho", "1.9e-5", "--json",
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    document = json.loads(result.stdout)
    designs = _designs(document)
    assert len(designs) == 1
    assert document["distance_m"] <= 600
    assert document["n_trials"] <= 40
    assert document["distance_m"] == pytest.approx(sum(d.distance_m * n for d, n in designs))
    expected = expected_standard_errors(designs, NOMAD150, default_description(0.001))
    errors = document["expected_stderr"]
    for name, se in zip(PARAMETER_NAMES, expected, strict=True):
        assert errors[name]["stderr_si"] == pytest.approx(se, rel=1e-9)
    # paper units: E_R deg/m, K_theta deg^2/m
    assert errors["E_R"]["stderr_paper"] == pytest.approx(math.degrees(expected[0]))
    assert errors["E_R"]["target_si"] == pytest.approx(math.radians(0.004))
    assert errors["K_theta"]["target_si"] == pytest.approx(0.003 * (math.pi / 180) ** 2)
    ratios = [errors[n]["ratio_to_target"] for n in PARAMETER_NAMES]
    assert document["meets_targets"] == (max(ratios) <= 1.0)
    assert document["criterion"] == pytest.approx(max(ratios))


def test_table_output_with_a_robot_description(tmp_path: Path) -> None:
    robot = tmp_path / "robot.toml"
    robot.write_text(ROBOT_TOML)
    result = run("--budget-m", "200", "--max-trials", "20", "--max-designs", "1",
                 "--robot", str(robot), "--json")  # fmt: skip
    assert result.returncode == 0, result.stderr
    document = json.loads(result.stdout)
    expected = expected_standard_errors(_designs(document), NOMAD150, load_robot_description(robot))
    assert document["expected_stderr"]["K_rho"]["stderr_si"] == pytest.approx(expected[3])
    table = run("--budget-m", "60", "--max-trials", "10", "--max-designs", "1",
                "--robot", str(robot))  # fmt: skip
    assert table.returncode == 0, table.stderr
    assert "Recommended plan" in table.stdout
    assert "deg^2/m" in table.stdout


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (("--budget-m", "-5"), "budget"),
        (("--budget-m", "100", "--sigma-m", "0.001", "--robot", "create2"), "not both"),
        (("--budget-m", "100", "--sigma-m", "-1"), "sigma-m"),
        (("--budget-m", "100", "--robot", "/no/such/robot.toml"), "cannot read"),
        (("--budget-m", "100", "--target-E-R", "0"), "target-E-R"),
        (("--budget-m", "100", "--K-theta", "-0.1"), "K-theta"),
        (("--budget-m", "100", "--max-designs", "4"), "max-designs"),
        (("--budget-m", "0.2"), "no candidate design"),
    ],
)
def test_bad_input_exits_2_with_a_clear_message(args: tuple[str, ...], message: str) -> None:
    result = run(*args)
    assert result.returncode == 2
    assert message in result.stderr.replace("\n", " ").replace("│", " ")
