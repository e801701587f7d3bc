"""Both backends drive general paths (squares, polygons, circles as short legs
and turns, clockwise and counter-clockwise) through ``Robot.drive`` with the
safety of forth-and-back legs: every step checked before the first is sent,
each step checked against the encoders, a fault during a turn stops the robot
and raises, nothing is resent (issue 19).

In process through the URL handlers (``fakerobot://``, ``fakecreate2://``), and
the Nomad over a real pty (the Create 2's squares over a pty, at time scale 1:
tests/driver/test_path_truth.py).
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any

import pytest

import fakes  # noqa: F401  (registers the fake URL handlers)
from fakes.nomad.process import EmulatorProcess
from odohil.driver.create2.facts import STEP_TOLERANCE_M
from odohil.driver.create2.robot import MIN_STEP_TOLERANCES
from odohil.driver.nomad.motion import DEFAULT_TOLERANCE_WIRE
from odohil.driver.odometry import DriveSettings, TrialMotion
from odohil.errors import (
    DisconnectedError,
    MotionError,
    NakError,
    OdohilError,
    OdohilTimeoutError,
    ParameterError,
)
from odohil.protocol.create2.geometry import CREATE2_GEOMETRY
from odohil.protocol.create2.opcodes import Opcode
from odohil.protocol.nomad.wire_units import METRES_PER_WIRE_LENGTH, RADIANS_PER_WIRE_ANGLE
from odohil.science.path_designs import PathDesign, parse_path_design
from odohil.science.paths import EncoderPath, Leg, Turn
from odohil.session.robots.protocol import Robot
from odohil.session.robots.registry import open_robot

SETTINGS = DriveSettings(
    speed_m_s=0.5, turn_rate_rad_s=1.0, turn_acceleration_rad_s2=2.0, watchdog_s=0.0
)
URLS = {
    # the Nomad runs its own pr profile: fast-forwarded freely
    "nomad150": "fakerobot://?seed=1&time_scale=200",
    # the Create 2's host ends each step on 15 ms readings: time scale 10 with
    # the lag-absorbing clock, as the demo drives it (odohil/driver/create2/facts.py),
    # and its waits for the next reading skipped (the same readings at the same
    # simulated times, without sleeping; the wall clock is the pty test's below)
    "create2": "fakecreate2://?seed=1&time_scale=10&max_gap_ms=15&skip_waits=1",
}
PATHS = (
    "square:0.5,ccw",
    "square:0.5,cw",
    "polygon:5,0.4,ccw",
    "polygon:5,0.4,cw",
    "circle:0.5,12,ccw",
    "circle:0.5,12,cw",
)


def step_tolerances(backend: str) -> tuple[float, float]:
    """How far one step may end from its target: (m, rad), from the drivers' constants."""
    if backend == "nomad150":
        return (
            DEFAULT_TOLERANCE_WIRE * METRES_PER_WIRE_LENGTH,
            DEFAULT_TOLERANCE_WIRE * RADIANS_PER_WIRE_ANGLE,
        )
    # per wheel; a turn's heading miss is the wheels' half difference over half the base
    return STEP_TOLERANCE_M, STEP_TOLERANCE_M / (CREATE2_GEOMETRY.wheel_base_m / 2.0)


def closure_bound(backend: str, path: EncoderPath) -> tuple[float, float]:
    """How far a closed path's encoder end pose may be from its start when every
    step ends within its tolerance: (m, rad). The Nomad checks each step from the
    last one's end (misses add up); the Create 2 counts its targets from the
    trial's start (a miss is made up by the next step of its kind)."""
    metres, radians = step_tolerances(backend)
    n_turns = sum(isinstance(step, Turn) for step in path.steps)
    n_legs = len(path.steps) - n_turns
    heading = radians * (n_turns if backend == "nomad150" else 1)
    return n_legs * metres + path.distance_m * heading, heading


def truth(robot: Robot) -> Any:
    """The fake's true state through its in-process port."""
    return robot.transport.truth()  # type: ignore[attr-defined]


def turn_commands(snapshot: Any) -> list[tuple[int, int]]:
    """The Create 2's Drive Direct commands with the wheels opposite: (right, left) mm/s."""
    out = []
    for command in snapshot.commands:
        if command.opcode != Opcode.DRIVE_DIRECT:
            continue
        data = bytes(command.data)
        right, left = (int.from_bytes(data[i : i + 2], "big", signed=True) for i in (0, 2))
        if right == -left != 0:
            out.append((right, left))
    return out


@contextmanager
def armed(backend: str, url: str) -> Iterator[Robot]:
    with open_robot(backend, url) as robot:
        robot.arm(SETTINGS)
        robot.settle(5.0)
        robot.zero()
        yield robot


def check_closed(backend: str, design: PathDesign, motion: TrialMotion) -> None:
    position, heading = closure_bound(backend, design.path())
    x, y, theta = motion.end_pose
    assert math.hypot(x, y) <= position, motion.end_pose
    assert abs(theta) <= heading, motion.end_pose
    assert not motion.end.moving


@pytest.mark.parametrize("text", PATHS)
@pytest.mark.parametrize("backend", sorted(URLS))
def test_each_backend_drives_closed_paths_both_ways(backend: str, text: str) -> None:
    design = parse_path_design(text)
    with armed(backend, URLS[backend]) as robot:
        motion = robot.drive(design, SETTINGS)
        check_closed(backend, design, motion)
        snapshot = truth(robot)
        assert not snapshot.moving
        if backend == "nomad150":
            # one pr per leg and per turn, none resent
            assert [r.command for r in snapshot.motion_log].count("pr") == len(design.path().steps)


@dataclass(frozen=True)
class Steps:
    """A Drivable made of given steps (what a plan or a trial file may hand a robot)."""

    steps: tuple[Leg | Turn, ...]

    def path(self) -> EncoderPath:
        return EncoderPath(self.steps, name="test path")

    def label(self) -> str:
        return "test path"


def sent_motion(backend: str, snapshot: Any) -> int:
    if backend == "nomad150":
        return sum(r.command == "pr" for r in snapshot.motion_log)
    return sum(c.opcode == Opcode.DRIVE_DIRECT for c in snapshot.commands)


@pytest.mark.parametrize("backend", sorted(URLS))
@pytest.mark.parametrize(
    ("steps", "what"),
    [
        # a turn of 0.05 degrees: below the Nomad's wire unit and the Create 2's encoders
        ((Leg(0.5), Turn(math.radians(0.05)), Leg(0.5)), "step 2 of 3"),
        # a leg of 3 mm: below either driver's shortest leg
        ((Leg(0.5), Turn(math.pi / 2), Leg(0.5), Turn(math.pi / 2), Leg(0.003)), "step 5 of 5"),
    ],
)
def test_a_step_out_of_range_is_refused_by_name_before_anything_moves(
    backend: str, steps: tuple[Leg | Turn, ...], what: str
) -> None:
    with armed(backend, URLS[backend]) as robot:
        with pytest.raises(ParameterError, match=what) as refused:
            robot.drive(Steps(steps), SETTINGS)
        assert "at least" in str(refused.value) or "must be" in str(refused.value)
        assert sent_motion(backend, truth(robot)) == 0
        assert not truth(robot).moving


@pytest.mark.parametrize("backend", sorted(URLS))
def test_a_path_longer_than_any_trial_may_be_is_refused_before_anything_moves(
    backend: str,
) -> None:
    # 126 legs of 80 m: each in both robots' leg range, 10,080 m in all
    with armed(backend, URLS[backend]) as robot:
        with pytest.raises(ParameterError, match="drives 10080 m in one trial; at most 10000 m"):
            robot.drive(Steps((Leg(80.0),) * 126), SETTINGS)
        assert sent_motion(backend, truth(robot)) == 0


def test_the_nomad_rounds_turns_on_their_running_sum_so_a_heptagon_closes() -> None:
    # 360/7 degrees is 514.29 tenths: seven turns of 514 would leave 2 tenths open
    design = parse_path_design("circle:0.5,7")
    with armed("nomad150", URLS["nomad150"]) as robot:
        motion = robot.drive(design, SETTINGS)
        steers = [r.args[1] for r in truth(robot).motion_log if r.command == "pr" and r.args[1]]
    assert sorted(set(steers)) == [514, 515]
    assert sum(steers) == 3600
    assert abs(motion.end_pose[2]) <= DEFAULT_TOLERANCE_WIRE * RADIANS_PER_WIRE_ANGLE


def test_the_create2_refuses_arc_turns_it_could_only_drive_in_place() -> None:
    steps = (Leg(0.3), Turn(0.5, "arc"), Leg(0.3))
    with armed("create2", URLS["create2"]) as robot:
        with pytest.raises(ParameterError, match=r"step 2 of 3 .*is an arc turn"):
            robot.drive(Steps(steps), SETTINGS)
        assert sent_motion("create2", truth(robot)) == 0


def test_the_create2_refuses_a_circle_whose_turns_its_end_check_cannot_tell_from_none() -> None:
    # a 40-gon's 9 degree turns are under twice the turn's end tolerance
    with armed("create2", URLS["create2"]) as robot:
        with pytest.raises(ParameterError, match=r"step 2 of 80 .*turn 0\.15708 rad") as refused:
            robot.drive(parse_path_design("circle:1,40"), SETTINGS)
        assert f"{MIN_STEP_TOLERANCES:g} x its end-of-step tolerance" in str(refused.value)
        assert sent_motion("create2", truth(robot)) == 0


# ---- faults during the first turn of a square ---------------------------------------------
NOMAD_TURN_FAULTS: dict[str, tuple[type[OdohilError], int]] = {
    # the second pr of a square is its first turn: the error, and the pr executed
    "stuck:pr@2": (OdohilTimeoutError, 2),
    "watchdog:pr@2": (MotionError, 2),
    "disconnect:pr@2": (DisconnectedError, 2),
    "nak:pr@2": (NakError, 1),  # a NAKed pr is not executed
}


@pytest.mark.parametrize(("fault", "expected"), NOMAD_TURN_FAULTS.items())
def test_a_nomad_fault_during_a_turn_stops_the_robot_and_resends_nothing(
    fault: str, expected: tuple[type[OdohilError], int]
) -> None:
    error, executed = expected
    with armed("nomad150", f"fakerobot://?seed=2&time_scale=50&fault={fault}") as robot:
        with pytest.raises(error):
            robot.drive(
                parse_path_design("square:0.3,cw"),
                # stuck: the turn never ends; its limit is this cap (1 s, not the
                # 120 s default), far above the fast-forwarded leg before it
                DriveSettings(speed_m_s=0.5, turn_rate_rad_s=1.0, step_timeout_s=1.0),
            )
        snapshot = truth(robot)
        log = [r.command for r in snapshot.motion_log]
        assert log.count("pr") == executed
        assert snapshot.faults_fired
        if not snapshot.disconnected:  # a cut line carries no st: the watchdog's job
            assert log[-1] == "st"
            assert not snapshot.moving


# a square of 0.3 m: the first leg drives 0.3 m, its first turn each wheel 0.18 m more
CREATE2_TURN_FAULTS: dict[str, type[OdohilError]] = {
    "stall@0.4": MotionError,
    "mute@0.4": OdohilTimeoutError,
    "disconnect@0.4": DisconnectedError,
}


@pytest.mark.parametrize(("fault", "error"), CREATE2_TURN_FAULTS.items())
def test_a_create2_fault_during_a_turn_stops_the_robot_and_resends_nothing(
    fault: str, error: type[OdohilError]
) -> None:
    url = f"fakecreate2://?seed=2&time_scale=4&max_gap_ms=15&skip_waits=1&fault={fault}"
    with armed("create2", url) as robot:
        with pytest.raises(error):
            robot.drive(parse_path_design("square:0.3,cw"), SETTINGS)
        snapshot = truth(robot)
        assert snapshot.faults_fired
        if not snapshot.disconnected:
            # a cut line cannot carry the stop: the OI has no watchdog (docs/create2.md)
            assert snapshot.left_mm_s == snapshot.right_mm_s == 0.0
        turns = turn_commands(snapshot)
        # the turn started once (at its speed, perhaps then at the crawl), never again
        assert turns
        assert turns[0][0] < 0  # cw: the right wheel backwards
        assert len(turns) <= 2
        assert len({right for right, _ in turns}) == len(turns)
        last = snapshot.commands[-1]
        if not snapshot.disconnected:
            assert last.opcode == Opcode.DRIVE_DIRECT
            assert bytes(last.data) == bytes(4)


# ---- over a real pty ------------------------------------------------------------------------
def test_a_square_over_a_real_pty() -> None:
    """The Nomad's fake as a process on a pty (time scale 20). The Create 2's
    square over a pty at time scale 1, with this check of its closing, is
    tests/driver/test_path_truth.py's (both ways, the truth at every step)."""
    design = parse_path_design("square:0.2,cw")
    process = EmulatorProcess(["--seed", "4", "--time-scale", "20", "--no-pacing"])
    with process, open_robot("nomad150", process.device) as robot:
        robot.arm(SETTINGS)
        robot.settle(5.0)
        robot.zero()
        motion = robot.drive(design, SETTINGS)
        check_closed("nomad150", design, motion)
        assert not process.truth().moving
