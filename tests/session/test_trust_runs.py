"""Issue 8, acceptance: unattended sessions over several seeds end either
trusted and within 4 standard errors of the fake's truth (the reported
4-sigma-equivalent interval, ``ci_4sigma``, docs/estimation.md), or with exit 3
and the reason (``verdict.reasons``).

Runs the real ``odohil run ... --measure fake --json`` in process (typer's
CliRunner on odohil.cli.app's app: the same parsing, session and rendering as
the console script, without a process start per run) against the fake robot
(``fakerobot://``), with the README's robot description (two cross
distances). The fake runs at the paper's Nomad 150 values, fast-forwarded
(:data:`TIME_SCALE`).
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from typer.testing import CliRunner, Result

from odohil.cli.app import app
from odohil.science.parameters import NOMAD150, PARAMETER_NAMES

README = Path(__file__).resolve().parents[2] / "README.md"
PLANS = ("k=1,l=2,n=20;k=0.5,l=2,n=20", "k=1,l=3,n=15;k=10,l=0.5,n=15")
SEEDS = (1, 2, 11)
LIMIT_SE = 4.0
TIME_SCALE = 20000
"""The fake's time scale. Its moves are trapezoids settled on its own clock and
its errors drawn per segment of distance, so a session's data do not follow
the time scale: seeds 2 and 11 at 2000 and at 20000 gave the same verdicts and
estimates within 2e-8 of each other (relative; the real-clock runs at one scale
differ as much, a turn's true heading being summed per poll slice). At 2000 the
host's 2 ms polls while the fake moved were about a third of each session's
wall time."""


def readme_robot() -> str:
    """The robot.toml of the README's quick start."""
    text = README.read_text(encoding="utf-8")
    block = text.split("```toml", 1)[1].split("```", 1)[0]
    return "\n".join(line.strip() for line in block.strip().splitlines()) + "\n"


def one_cross_robot() -> str:
    """The README's robot with only its first cross distance."""
    return readme_robot().replace('[["A", "B"], ["B", "C"]]', '[["A", "B"]]')


def _run(tmp_path: Path, plan: str, seed: int, robot_toml: str | None = None) -> Result:
    robot = tmp_path / "robot.toml"
    robot.write_text(robot_toml or readme_robot(), encoding="utf-8")
    port = f"fakerobot://?seed={seed}&time_scale={TIME_SCALE}"
    args = [
        "run",
        "--allow-few-trials",
        "--port",
        port,
        "--robot",
        str(robot),
        "--plan",
        plan,
        "--measure",
        "fake",
    ]
    return CliRunner().invoke(app, [*args, "--session", str(tmp_path / "s"), "--json"])


def test_readme_robot_has_two_cross_distances() -> None:
    assert '[["A", "B"], ["B", "C"]]' in readme_robot()
    assert '[["A", "B"]]' in one_cross_robot()


def test_one_way_plan_with_one_cross_distance_is_refused_before_motion(tmp_path: Path) -> None:
    """Measured: with one cross distance this plan exited 0 with K_theta 5e4 times
    its truth (mirror poses). Now pre-flight refuses it, naming the design."""
    done = _run(tmp_path, PLANS[0], 11, one_cross_robot())
    assert done.exit_code == 2, done.stderr
    message = " ".join(done.stderr.split())
    assert "k=0.5 l=2 m turn is a one-way design" in message
    assert "measurement.cross" in message
    assert not (tmp_path / "s").exists()


def _check(done: Result, expected_exit: int) -> None:
    """Right or says why not; and the verdict these seeded sessions got (exit 0
    trusted, 3 not trusted) asserted exactly, so that a flip is seen."""
    assert done.exit_code == expected_exit, done.stderr
    result = json.loads(done.stdout.strip().splitlines()[-1])
    if done.exit_code == 3:
        assert result["verdict"]["reasons"], result.get("verdict")
        return
    truth = NOMAD150.to_si_dict()
    for name in PARAMETER_NAMES:
        p = result["parameters"][name]
        if "ci_4sigma" in p:  # the 4-sigma-equivalent interval the user is given
            low, high = p["ci_4sigma"]
            low = float("-inf") if low is None else low
            high = float("inf") if high is None else high
            assert low <= truth[name] <= high, f"{name}: {truth[name]} outside {low}..{high}"
            continue
        off = abs(p["value"] - truth[name]) / p["stderr"]
        assert off <= LIMIT_SE, f"{name}: {p['value']} is {off:.1f} SE from {truth[name]}"


@pytest.mark.slow
@pytest.mark.parametrize("plan", PLANS)
@pytest.mark.parametrize("seed", SEEDS)
def test_session_is_right_or_says_why_not(tmp_path: Path, plan: str, seed: int) -> None:
    _check(_run(tmp_path, plan, seed), 0)


@pytest.mark.slow
@pytest.mark.parametrize("seed", SEEDS)
def test_closed_plan_with_one_cross_distance(tmp_path: Path, seed: int) -> None:
    """Measured: seeds 1 and 2 ended E_T 6.2 and 7.6 SE off with exit 0. Now seed
    2 ends not trusted (exit 3, with reasons), seeds 1 and 11 trusted and right."""
    _check(_run(tmp_path, PLANS[1], seed, one_cross_robot()), 3 if seed == 2 else 0)
