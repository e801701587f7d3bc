"""Robot backends declare their facts (issue 18): one typed value per backend,
read through the registry; the session and the CLI ask it, never a robot's
name or getattr. Each test here failed on the code before (see its docstring)."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest
from typer.testing import CliRunner

import fakes
from odohil.cli.app import app
from odohil.errors import ParameterError, RobotDescriptionError, StopUnconfirmedError
from odohil.protocol.nomad.limits import check_leg_length_m
from odohil.science.robot_facts import RobotFacts
from odohil.session.plans.plan import check_session_plan, parse_plan
from odohil.session.robots.registry import (
    backend_names,
    fake_hooks,
    open_robot,
    parse_description,
    robot_facts,
)

ROOT = Path(__file__).resolve().parents[2]
BACKENDS = ("nomad150", "create2")
FAKE_PORTS = {"nomad150": "fakerobot://?seed=3", "create2": "fakecreate2://?seed=3&time_scale=4"}
BASE = """
[screws]
A = [0.20, 0.0]
B = [-0.10, 0.173]
C = [-0.10, -0.173]
[measurement]
sigma_m = 0.001
"""


def description(protocol: str, extra: str = "", serial: str = "") -> str:
    return (
        BASE
        + f'[robot]\nprotocol = "{protocol}"\n{extra}'
        + (f"[serial]\n{serial}" if serial else "")
    )


@pytest.mark.parametrize("protocol", BACKENDS)
def test_every_backend_declares_its_facts_in_one_typed_value(protocol: str) -> None:
    """Before: baud rates and the fake hooks were loose class attributes read
    with getattr; leg limits and turns lived outside the backend."""
    assert set(BACKENDS) <= set(backend_names())
    facts = robot_facts(protocol)
    assert isinstance(facts, RobotFacts)
    assert facts.name == protocol
    assert facts.default_baud in facts.baud_rates
    assert 0 < facts.min_leg_m < facts.max_leg_m
    hooks = fake_hooks(protocol)
    assert hooks is not None
    assert facts.fake is not None
    assert hooks.url_scheme == facts.fake.url_scheme
    assert FAKE_PORTS[protocol].startswith(hooks.url_scheme)


def test_a_plan_is_checked_against_its_own_robots_leg_limits() -> None:
    """Before: the Nomad's ``pr`` limit (83.2 m) applied to every robot."""
    plan = parse_plan("k=1,l=90,n=3,variant=reverse")
    assert check_session_plan(plan, "create2") is plan
    with pytest.raises(ParameterError, match=r"l must be .*83\.2.* Nomad 150"):
        check_session_plan(plan, "nomad150")


@pytest.mark.parametrize("leg_m", [0.03, 0.0499, 0.05, 0.06])
def test_the_nomads_minimum_leg_is_one_value(leg_m: float) -> None:
    """Before: the plan refused legs under 50 mm, the driver under 25.4 mm."""
    plan = parse_plan(f"k=1,l={leg_m},n=3")
    try:
        check_session_plan(plan, "nomad150")
        plan_ok = True
    except ParameterError:
        plan_ok = False
    try:
        check_leg_length_m(leg_m)
        driver_ok = True
    except ParameterError:
        driver_ok = False
    assert plan_ok == driver_ok == (leg_m >= robot_facts("nomad150").min_leg_m)


def test_the_description_is_checked_against_its_backends_line_speeds() -> None:
    """Before: only the Nomad's rates were known to the description (a
    Create 2 description with an OI-impossible baud was accepted)."""
    assert parse_description(description("create2", serial="baud = 19200\n")).serial.baud == 19200
    with pytest.raises(RobotDescriptionError, match=r"serial\.baud must be one of .* create2"):
        parse_description(description("create2", serial="baud = 12345\n"))
    with pytest.raises(RobotDescriptionError, match=r"serial\.baud must be one of .* nomad150"):
        parse_description(description("nomad150", serial="baud = 115200\n"))
    assert parse_description(description("create2")).serial.baud == 115200  # its default


def test_a_description_may_give_only_the_robot_keys_its_backend_reads() -> None:
    """Before: a Nomad 150 description took a differential drive's constants
    and silently ignored them."""
    with pytest.raises(RobotDescriptionError, match=r"unknown key\(s\) robot\.counts_per_rev"):
        parse_description(description("nomad150", "counts_per_rev = 512\n"))
    create2 = parse_description(description("create2", "counts_per_rev = 512\n")).robot
    nominal = robot_facts("create2").drive
    assert create2.drive is not None
    assert nominal is not None
    assert create2.drive.counts_per_rev == 512
    assert create2.drive.wheel_base_m == nominal.wheel_base_m


def test_geometry_keys_without_a_protocol_are_told_to_add_the_recorded_protocol() -> None:
    """Before (issue 30): only "unknown key(s) robot.counts_per_rev ...", no way out."""
    geometry = "[robot]\ncounts_per_rev = 2796.8\nwheel_diameter_m = 0.084\nwheel_base_m = 0.2\n"
    with pytest.raises(
        RobotDescriptionError,
        match=r"unknown key\(s\) robot\.counts_per_rev, robot\.wheel_diameter_m, "
        r"robot\.wheel_base_m;.*"
        r'add protocol = "recorded" to \[robot\]',
    ):
        parse_description(BASE + geometry)
    # a stated protocol, or a key no protocol reads, gets no such advice
    for text in (description("nomad150", "counts_per_rev = 512\n"), BASE + "[robot]\ncolour = 1\n"):
        with pytest.raises(RobotDescriptionError, match="unknown key") as refused:
            parse_description(text)
        assert "recorded" not in str(refused.value)
    recorded = parse_description(BASE + '[robot]\nprotocol = "recorded"\n' + geometry[8:]).robot
    assert recorded.drive is not None
    assert recorded.drive.wheel_base_m == 0.2


def test_turns_exact_defaults_to_the_backends_fact() -> None:
    for protocol in BACKENDS:
        robot = parse_description(description(protocol)).robot
        assert robot.turns_exact is robot_facts(protocol).turns_exact


ROBOT_FACT_ATTRIBUTES = {
    "baud_rates",
    "default_baud",
    "transport",
    "fake_url_scheme",
    "fake_truth_client",
    "facts",
}


def test_the_session_and_the_cli_read_no_robot_fact_with_getattr() -> None:
    """Before: line.py fetched ``baud_rates`` and run.py ``transport`` with
    getattr, robots.py the fake hooks."""
    offenders = []
    for layer in ("session", "cli"):
        for path in sorted((ROOT / "odohil" / layer).rglob("*.py")):
            for node in ast.walk(ast.parse(path.read_text())):
                if (
                    isinstance(node, ast.Call)
                    and isinstance(node.func, ast.Name)
                    and node.func.id in ("getattr", "hasattr")
                    and len(node.args) >= 2
                    and isinstance(node.args[1], ast.Constant)
                    and node.args[1].value in ROBOT_FACT_ATTRIBUTES
                ):
                    offenders.append(f"{path.relative_to(ROOT)}:{node.lineno}")
    assert offenders == []


def test_emulate_help_gives_each_robots_own_defaults() -> None:
    """Before: ``emulate --help`` named only the Nomad's fake and no per-robot default."""
    result = CliRunner().invoke(app, ["emulate", "--help"], env={"COLUMNS": "200"})
    assert result.exit_code == 0, result.output
    shown = " ".join(result.output.split())
    for protocol in BACKENDS:
        facts = robot_facts(protocol)
        assert f"{protocol} {facts.default_baud}" in shown
        assert facts.label in shown


def test_emulate_refuses_a_line_rate_the_robot_does_not_speak() -> None:
    result = CliRunner().invoke(app, ["emulate", "--robot", "nomad150", "--baud", "115200"])
    assert result.exit_code == 2, result.output
    assert "38400" in result.output


@pytest.mark.parametrize("protocol", BACKENDS)
def test_both_backends_stop_and_confirm_the_same_way(protocol: str) -> None:
    """One implementation (odohil/driver/stopping.py): the same confirmation
    and the same refusal once the line is closed. Before: the Create 2 said
    "line closed", the Nomad "the line is closed", each from its own loop."""
    fakes.register_url_handlers()  # as the CLI does for a fake's URL; not left to another test
    robot = open_robot(protocol, FAKE_PORTS[protocol], None, None)
    with robot:
        assert not robot.settle(2.0).moving
        assert not robot.stop_and_confirm(2.0).moving
    with pytest.raises(
        StopUnconfirmedError,
        match=r"^the robot did not report that it stopped within 0\.5 s: the line is closed$",
    ):
        robot.stop_and_confirm(0.5)
    with pytest.raises(ParameterError, match="timeout must be finite"):
        robot.stop_and_confirm(float("nan"))
