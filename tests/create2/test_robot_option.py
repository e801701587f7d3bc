"""``--robot`` by built-in name, the description's [robot] settings reaching
the backend, and turn-free calibration of a robot whose turns carry error
(issue 12, items 4 and 5), through the console command's parsing, session and
rendering in process (typer's CliRunner on odohil.cli.app's app): no test here
needs a process of its own."""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import pytest
from typer.testing import CliRunner

import fakes
from odohil.cli.app import app
from odohil.driver.create2.robot import Create2Robot
from odohil.driver.nomad.backend import NomadBackend
from odohil.science.diff_drive import DiffDriveGeometry
from odohil.session.journal.state import load_session
from odohil.session.robots.description import builtin_names, builtin_path, load_robot_description
from odohil.session.robots.line import resolve_line
from odohil.session.robots.registry import open_robot
from odohil.session.robots.registry import parse_description as parse_robot_description

fakes.register_url_handlers()

FAKE = "fakecreate2://?seed=1&time_scale=10&max_gap_ms=15&skip_waits=1"


@dataclass(frozen=True)
class Done:
    """What ``odohil ARGS`` ended with: exit status and its two streams."""

    returncode: int
    stdout: str
    stderr: str


def odohil(*args: str | Path) -> Done:
    """``odohil ARGS`` in process (CliRunner), as the console script parses and renders it."""
    done = CliRunner().invoke(app, [str(a) for a in args])
    return Done(done.exit_code, done.stdout, done.stderr)


def test_the_builtin_descriptions_parse_with_their_robot_constants() -> None:
    assert builtin_names() == ("create2", "nomad150")
    create2 = load_robot_description(builtin_path("create2")).robot
    assert create2.protocol == "create2"
    assert create2.drive == DiffDriveGeometry(508.8, 0.072, 0.235)
    assert create2.turns_exact is False
    nomad = load_robot_description(builtin_path("nomad150")).robot
    assert (nomad.protocol, nomad.turns_exact) == ("nomad150", True)


def test_turns_exact_defaults_by_protocol_and_is_checked() -> None:
    base = builtin_path("nomad150").read_text().replace('protocol = "nomad150"\n', "")
    base = base.replace("turns_exact = true\n", "").replace("baud = 38400", "")
    assert parse_robot_description(base).robot.turns_exact is True
    other = base.replace("[robot]", '[robot]\nprotocol = "create2"')
    assert parse_robot_description(other).robot.turns_exact is False
    with pytest.raises(Exception, match=r"robot\.turns_exact must be true or false"):
        parse_robot_description(base.replace("[robot]", "[robot]\nturns_exact = 1"))


def test_the_description_constants_reach_the_backend_opened_by_name(tmp_path: Path) -> None:
    text = builtin_path("create2").read_text().replace("0.072", "0.0731").replace("508.8", "512")
    description = parse_robot_description(text)
    line = resolve_line(description, FAKE, None)
    with open_robot(line.protocol, line.port, line.baud, line.robot) as robot:
        assert isinstance(robot, Create2Robot)
        assert robot.geometry == DiffDriveGeometry(512.0, 0.0731, 0.235)


def test_the_nomad_backend_accepts_and_ignores_the_robot_settings() -> None:
    settings = load_robot_description(builtin_path("nomad150")).robot
    with open_robot("nomad150", "fakerobot://?seed=1", None, settings) as robot:
        assert isinstance(robot, NomadBackend)


@pytest.mark.parametrize(
    "args",
    [
        ["plan", "--budget-m", "50"],
        ["estimate", "nothing.csv"],
        ["export", "nothing.csv"],
        ["validate", "nowhere"],
        ["run", "--allow-few-trials", "--plan", "k=1,l=1,n=2", "--measure", "fake"],
        ["wizard"],
        ["demo"],
        ["emulate"],
    ],
)
def test_an_unknown_robot_name_exits_2_naming_the_option_and_the_names(args: list[str]) -> None:
    done = odohil(*args, "--robot", "roomba9000")
    assert done.returncode == 2, done.stderr
    flat = " ".join(done.stderr.replace("│", " ").split())
    assert "--robot" in flat
    assert "roomba9000" in flat
    assert "create2, nomad150" in flat
    assert "cannot read" in flat


def test_the_planner_recommends_turn_free_designs_for_the_create2() -> None:
    create2 = json.loads(odohil("plan", "--robot", "create2", "--budget-m", "60", "--json").stdout)
    assert {d["variant"] for d in create2["designs"]} == {"reverse"}
    nomad = json.loads(odohil("plan", "--robot", "nomad150", "--budget-m", "60", "--json").stdout)
    assert "turn" in {d["variant"] for d in nomad["designs"]}
    given = odohil("plan", "--robot", "create2", "--evaluate", "k=1,l=2,n=20", "--json")
    assert {d["variant"] for d in json.loads(given.stdout)["designs"]} == {"reverse"}
    asked = odohil("plan", "--robot", "create2", "--evaluate", "k=1,l=2,n=20,variant=turn")
    assert "warning: turn designs on a robot whose turns carry error" in asked.stderr


def test_run_refuses_a_turn_plan_on_the_create2_before_anything_moves(tmp_path: Path) -> None:
    done = odohil(
        "run", "--allow-few-trials", "--robot", "create2", "--port", FAKE, "--measure", "fake",
        "--plan", "k=1,l=0.5,n=4,variant=turn", "--session", tmp_path / "s",
    )  # fmt: skip
    assert done.returncode == 2, done.stderr
    flat = " ".join(done.stderr.split())
    assert "turns_exact = false" in flat
    assert "--allow-turns" in flat
    assert not (tmp_path / "s").exists()


@pytest.fixture(scope="module")
def turn_trials(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Turn-variant trials of the paper's model (exact turns), two designs."""
    folder = tmp_path_factory.mktemp("turns")
    rows: list[str] = []
    for k, l_m, seed in (("1", "2", "1"), ("0.5", "2", "2")):
        out = folder / f"k{k}.csv"
        done = odohil(
            "simulate", "--k", k, "--l", l_m, "--trials", "20", "--out", out, "--seed", seed,
            "--variant", "turn",
        )  # fmt: skip
        assert done.returncode == 0, done.stderr
        lines = out.read_text().splitlines()
        rows += lines if not rows else lines[1:]
    combined = folder / "turns.csv"
    combined.write_text("\n".join(rows) + "\n")
    return combined


def test_turn_trials_of_a_robot_whose_turns_carry_error_are_not_trusted(turn_trials: Path) -> None:
    nomad = odohil("estimate", turn_trials, "--robot", "nomad150", "--json")
    assert nomad.returncode == 0, nomad.stderr
    assert json.loads(nomad.stdout)["verdict"]["status"] == "trusted"
    create2 = odohil("estimate", turn_trials, "--robot", "create2", "--json")
    assert create2.returncode == 3, create2.stderr
    verdict = json.loads(create2.stdout)["verdict"]
    assert verdict["status"] == "doubtful"
    assert any("turn trials on a robot whose turns carry error" in r for r in verdict["reasons"])


@pytest.mark.slow
def test_run_with_allow_turns_defaults_to_reverse_and_is_not_trusted(tmp_path: Path) -> None:
    # two trials a design are enough: the verdict's reason is the plan's turn
    # trials, not their number (was n=6 each: 12 trials at time scale 10)
    done = odohil(
        "run", "--allow-few-trials",
        "--robot", "create2", "--port", FAKE, "--measure", "fake", "--allow-turns",
        "--plan", "k=1,l=0.5,n=2,variant=turn;k=0.5,l=0.5,n=2", "--session", tmp_path / "s",
        "--json",
    )  # fmt: skip
    assert done.returncode == 3, done.stderr
    assert "warning: turn designs on a robot whose turns carry error" in done.stderr
    plan = load_session(tmp_path / "s").state.plan
    assert plan is not None
    assert [item.design.variant for item in plan.items] == ["turn", "reverse"]
    verdict = json.loads(done.stdout)["verdict"]
    assert verdict["status"] == "doubtful"
    assert any("turn trials on a robot whose turns carry error" in r for r in verdict["reasons"])
