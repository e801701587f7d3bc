"""What the CLI used to work out itself and now asks the session layer for
(issue 18, "the CLI only parses, calls and renders"), tested in process."""

from __future__ import annotations

import math
import os
import signal
import time
from pathlib import Path

import pytest

from odohil.driver.odometry import OdometrySample
from odohil.errors import MeasurementError, ParameterError, RobotDescriptionError
from odohil.science.paths import Design
from odohil.session.addresses import SOCKET_PATH_MAX, check_socket_path
from odohil.session.commands.demo import DEMO_PLAN, TURN_FREE_PLAN, demo_session
from odohil.session.results.outcome import parse_exclude
from odohil.session.robots.description import builtin_path, resolve_robot, robot_protocol
from odohil.session.robots.registry import emulated_backends, emulator
from odohil.session.signals import ctrl_c_in_words
from odohil.session.wizard.motion_steps import MotionSteps, pose_text, step_fraction


def _at(x: float, y: float = 0.0, theta: float = 0.0, moving: bool = True) -> OdometrySample:
    return OdometrySample(0.0, 0.0, x, y, theta, moving)


def test_motion_steps_follow_a_forth_and_back_motion() -> None:
    steps = MotionSteps(Design(1, 0.5, "turn"))  # leg, turn, leg, turn
    assert steps.sample(_at(0.0, moving=False)) is None  # before the first step
    assert steps.sample(_at(0.25)) == pytest.approx(0.5)  # half the first leg
    assert steps.sample(_at(0.9)) == pytest.approx(1.0)  # no more than the step
    assert steps.sample(_at(0.5, moving=False)) == pytest.approx(1.0)  # at rest: step ends
    assert steps.sample(_at(0.5, theta=math.pi / 2)) == pytest.approx(1.5)  # half the turn
    assert steps.sample(_at(0.5, theta=math.pi, moving=False)) == pytest.approx(2.0)


def test_a_step_fraction_is_not_capped_and_a_sample_reads_as_a_pose() -> None:
    leg = Design(1, 0.5, "turn").path().steps[0]
    assert step_fraction(leg, _at(0.0), _at(0.0, 1.0)) == pytest.approx(2.0)
    assert pose_text(_at(0.1, -0.002, math.radians(12))) == (
        "x=+0.100 m y=-0.002 m heading=  12.0 deg"
    )


def test_the_demo_runs_turn_free_on_a_robot_whose_turns_carry_error(tmp_path: Path) -> None:
    nomad = demo_session("nomad150", 3, tmp_path / "n")
    create2 = demo_session("create2", 3, tmp_path / "c")
    assert (nomad.spec.plan, create2.spec.plan) == (DEMO_PLAN, TURN_FREE_PLAN)
    assert nomad.port.startswith("fakerobot://?seed=3&")
    assert create2.port.startswith("fakecreate2://?seed=3&")
    assert nomad.spec.settings == {"truth": dict(nomad.truth)}
    assert 'protocol = "create2"' in (create2.spec.robot_toml or "")


def test_a_robot_is_a_file_or_a_builtin_name(tmp_path: Path) -> None:
    assert resolve_robot("create2") == builtin_path("create2")
    mine = tmp_path / "create2"
    mine.write_text("")
    assert resolve_robot(mine) == mine  # a file of that name wins
    with pytest.raises(RobotDescriptionError, match="not the name of a built-in"):
        resolve_robot(tmp_path / "nothing.toml")
    assert robot_protocol("nomad150") == "nomad150"


def test_the_emulated_backends_and_their_emulators() -> None:
    names = [facts.name for facts in emulated_backends()]
    assert {"nomad150", "create2"} <= set(names)
    facts, hooks, serve = emulator("create2")
    assert (facts.name, hooks.url_scheme, callable(serve)) == ("create2", "fakecreate2:", True)


def test_a_truth_socket_path_must_fit_a_unix_socket(tmp_path: Path) -> None:
    check_socket_path(str(tmp_path / "truth.sock"))
    with pytest.raises(ParameterError, match=f"1 to {SOCKET_PATH_MAX} bytes"):
        check_socket_path("/tmp/" + "x" * SOCKET_PATH_MAX)
    with pytest.raises(ParameterError, match="does not exist"):
        check_socket_path(str(tmp_path / "gone" / "truth.sock"))


def test_exclude_is_a_list_of_trial_numbers() -> None:
    assert parse_exclude(None) == parse_exclude(" ") == frozenset()
    assert parse_exclude("3, 17,3") == frozenset({3, 17})
    with pytest.raises(MeasurementError, match="--exclude: '0' is not a trial number"):
        parse_exclude("1,0")


def _press_ctrl_c() -> None:
    os.kill(os.getpid(), signal.SIGINT)
    time.sleep(5)  # the handler raises first


def test_ctrl_c_says_its_name() -> None:
    with pytest.raises(KeyboardInterrupt, match="Ctrl-C"), ctrl_c_in_words():
        _press_ctrl_c()
