"""The Nomad backend as the session's ``Robot`` (odohil/driver/nomad/backend.py),
against the in-process fake robot: robot-neutral SI values, converted once."""

from __future__ import annotations

import math
from typing import Any

import pytest

import fakes  # noqa: F401  (registers the fakerobot:// URL handler)
from odohil.driver.nomad.backend import NomadBackend
from odohil.driver.odometry import DriveSettings, OdometrySample
from odohil.errors import StopUnconfirmedError
from odohil.science.paths import Design
from odohil.session.robots.protocol import Robot
from odohil.session.robots.registry import find_backend, open_robot

FAST = DriveSettings(speed_m_s=1.0, turn_rate_rad_s=3.0, watchdog_s=0.0)


def _open(query: str = "seed=1&time_scale=2000") -> NomadBackend:
    robot = open_robot("nomad150", f"fakerobot://?{query}")
    assert isinstance(robot, NomadBackend)
    return robot


def test_the_registry_finds_the_nomad_backend_by_name() -> None:
    assert find_backend("nomad150") is NomadBackend
    robot: Robot = _open()  # a Robot, structurally
    with robot:
        assert robot.port.startswith("fakerobot://")
        assert not robot.odometry().moving


def test_drive_hands_every_sample_up_in_si_with_the_step_ends_at_rest() -> None:
    seen: list[OdometrySample] = []
    with _open() as robot:
        robot.arm(FAST)
        robot.settle(5.0)
        zeroed = robot.zero()
        assert (zeroed.x_m, zeroed.y_m, zeroed.theta_rad) == (0.0, 0.0, 0.0)
        motion = robot.drive(Design(1, 0.5), FAST, seen.append)
    assert list(motion.samples) == seen  # the first is taken before the first step
    assert not seen[0].moving
    assert not seen[-1].moving
    at_rest = [s for s in seen[1:] if not s.moving]
    assert len(at_rest) == len(Design(1, 0.5).path().steps)  # one rest per leg or turn
    assert all(-math.pi < s.theta_rad <= math.pi for s in seen)
    x, y, theta = motion.end_pose
    assert abs(x) < 0.01
    assert abs(y) < 0.01
    assert abs(theta) < 0.01
    assert "(0.1 in)" in seen[-1].wire  # the wire view, for messages only


def test_zero_sets_the_odometry_to_a_pose() -> None:
    with _open() as robot:
        sample = robot.zero((0.5, -0.25, -math.pi / 2))
    assert sample.x_m == pytest.approx(0.5, abs=0.00254)
    assert sample.y_m == pytest.approx(-0.25, abs=0.00254)
    assert sample.theta_rad == pytest.approx(-math.pi / 2, abs=math.radians(0.1))


def test_close_stops_and_a_closed_robot_cannot_confirm_a_stop() -> None:
    robot: Any = _open()
    with robot:
        robot.stop()
        assert not robot.stop_and_confirm(2.0).moving
    robot.close()  # idempotent
    with pytest.raises(StopUnconfirmedError):
        robot.stop_and_confirm(0.5)
