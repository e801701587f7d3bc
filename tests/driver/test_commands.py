"""Every driver command against the in-process fake robot (fakerobot://)."""

from __future__ import annotations

import math
import os
import time

import pytest

from odohil.driver.nomad.link import open_port
from odohil.driver.nomad.robot import NomadRobot
from odohil.driver.nomad.sample import EncoderSample
from odohil.errors import ConnectionFailedError, ParameterError
from odohil.protocol.nomad.wire_units import metres_to_wire

from .helpers import fake_robot


def test_state_at_start_is_the_origin() -> None:
    with fake_robot() as fake:
        sample = fake.robot.state()
        assert (sample.x_wire, sample.y_wire, sample.steer_wire) == (0, 0, 0)
        assert not sample.moving
        assert sample.host_time_s <= time.monotonic()


def test_define_pose_and_angles_are_reported_back() -> None:
    with fake_robot() as fake:
        fake.robot.define_pose(0.254, -0.0254)
        fake.robot.define_angles(math.radians(-90.0), math.radians(45.0))
        sample = fake.robot.state()
        assert (sample.x_wire, sample.y_wire) == (100, -10)
        # Angles are reported reduced modulo 3600 (CHOICE C6).
        assert (sample.steer_wire, sample.turret_wire) == (2700, 450)
        assert sample.steer_rad == pytest.approx(math.radians(270.0))


def test_move_relative_then_wait_stopped_ends_where_commanded() -> None:
    with fake_robot() as fake:
        robot = fake.robot
        robot.set_watchdog(5)
        robot.set_accelerations(0.5, 1.0, 1.0)
        robot.set_speeds(0.5, 1.0, 1.0)
        sent = robot.move_relative(0.3, 0.0)
        assert sent.trans == metres_to_wire(0.3)
        end = robot.wait_stopped(10.0)
        assert not end.moving
        assert (end.x_wire, end.y_wire) == (sent.trans, 0)
        turn = robot.move_relative(0.0, math.radians(90.0))
        end = robot.wait_stopped(10.0)
        assert end.steer_wire == turn.steer == 900
        assert fake.commands("pr") == 2


def test_poll_until_stopped_streams_samples_in_time_order() -> None:
    with fake_robot() as fake:
        robot = fake.robot
        robot.set_speeds(0.5, 1.0, 1.0)
        robot.set_accelerations(0.5, 1.0, 1.0)
        robot.move_relative(-0.2, 0.0)
        seen: list[EncoderSample] = []
        end = robot.poll_until_stopped(10.0, seen.append)
        assert len(seen) >= 3
        assert seen[-1] == end
        times = [s.host_time_s for s in seen]
        assert times == sorted(times)
        xs = [s.x_wire for s in seen]
        assert xs == sorted(xs, reverse=True)
        assert any(s.moving for s in seen)
        assert end.x_wire == -metres_to_wire(0.2)


def test_stop_limp_and_zero() -> None:
    with fake_robot("seed=2&time_scale=200") as fake:
        robot = fake.robot
        robot.set_speeds(0.5, 1.0, 1.0)
        robot.set_accelerations(0.5, 1.0, 1.0)
        robot.move_relative(1.0, 0.0)
        assert robot.stop().x_wire < metres_to_wire(1.0)
        assert not robot.wait_stopped(5.0).moving
        robot.limp()
        zeroed = robot.zero()
        assert (zeroed.x_wire, zeroed.y_wire, zeroed.steer_wire) == (0, 0, 0)
        assert [r.command for r in fake.truth().motion_log] == ["pr", "st", "lp", "zr"]


def test_close_sends_st() -> None:
    with fake_robot() as fake:
        fake.robot.set_speeds(0.5, 1.0, 1.0)
        fake.robot.set_accelerations(0.5, 1.0, 1.0)
        fake.robot.move_relative(1.0, 0.0)
        fake.robot.close()
        assert fake.truth().motion_log[-1].command == "st"
        assert fake.settles()


@pytest.mark.parametrize(
    ("call", "args"),
    [
        ("set_watchdog", (256.0,)),
        ("set_speeds", (-0.1, 0.0, 0.0)),
        ("set_accelerations", (math.nan, 0.0, 0.0)),
        ("define_pose", (100.0, 0.0)),
        ("move_relative", (84.0, 0.0)),
    ],
)
def test_out_of_range_arguments_raise_before_sending(call: str, args: tuple[float, ...]) -> None:
    with fake_robot() as fake:
        requests = fake.robot.link.stats.requests
        with pytest.raises(ParameterError):
            getattr(fake.robot, call)(*args)
        assert fake.robot.link.stats.requests == requests


def test_unsupported_baud_is_refused() -> None:
    with pytest.raises(ParameterError):
        open_port("fakerobot://?seed=1", 57600)


def test_port_that_does_not_open() -> None:
    with pytest.raises(ConnectionFailedError):
        NomadRobot.connect("/dev/odohil-no-such-port")


def test_silent_line_fails_to_connect_within_the_first_byte_timeout() -> None:
    master, slave = os.openpty()
    try:
        started = time.monotonic()
        with pytest.raises(ConnectionFailedError):
            NomadRobot.connect(os.ttyname(slave))
        assert time.monotonic() - started < 3.0
    finally:
        os.close(master)
        os.close(slave)
