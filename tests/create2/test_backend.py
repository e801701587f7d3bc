"""The Create 2 backend found by name, its [robot] keys, and the
fakecreate2:// port through the same driver."""

from __future__ import annotations

import pytest

import fakes
from odohil.driver.create2.robot import Create2Robot
from odohil.driver.odometry import DriveSettings
from odohil.errors import RobotDescriptionError
from odohil.science.diff_drive import DiffDriveGeometry
from odohil.science.paths import Design
from odohil.science.robot_description import RobotSettings
from odohil.session.robots.registry import find_backend, open_robot
from odohil.session.robots.registry import parse_description as parse_robot_description

fakes.register_url_handlers()

BASE = """\
[screws]
A = [0.20, 0.0]
B = [-0.10, 0.173]
C = [-0.10, -0.173]
[measurement]
sigma_m = 0.001
"""


def test_create2_is_registered_by_name() -> None:
    backend = find_backend("create2")
    assert backend is Create2Robot
    assert backend.default_baud == 115200


def test_robot_keys_default_to_the_create2_and_are_checked() -> None:
    default = parse_robot_description(BASE + '[robot]\nprotocol = "create2"\n').robot
    assert default.drive == DiffDriveGeometry(508.8, 0.072, 0.235)
    assert default.full_mode is False
    given = parse_robot_description(
        BASE + "[robot]\nprotocol = 'create2'\ncounts_per_rev = 512\n"
        "wheel_diameter_m = 0.0725\nwheel_base_m = 0.2351\nfull_mode = true\n"
    ).robot
    assert given.drive == DiffDriveGeometry(512.0, 0.0725, 0.2351)
    assert given.full_mode is True
    with pytest.raises(RobotDescriptionError, match=r"robot\.wheel_base_m must be in \[0.02, 5\]"):
        parse_robot_description(BASE + "[robot]\nprotocol = 'create2'\nwheel_base_m = 0\n")
    with pytest.raises(RobotDescriptionError, match=r"robot\.full_mode must be true or false"):
        parse_robot_description(BASE + "[robot]\nprotocol = 'create2'\nfull_mode = 1\n")
    with pytest.raises(RobotDescriptionError, match=r"robot\.counts_per_rev"):
        parse_robot_description(BASE + "[robot]\nprotocol = 'create2'\ncounts_per_rev = 'many'\n")


def test_open_by_name_on_the_in_process_fake_drives_a_trial() -> None:
    with open_robot("create2", "fakecreate2://?seed=2&time_scale=4", None) as robot:
        assert isinstance(robot, Create2Robot)
        settings = DriveSettings(speed_m_s=0.3)
        robot.arm(settings)
        robot.zero()
        motion = robot.drive(Design(1, 0.5, "reverse"), settings)
        assert abs(motion.end_pose[0]) < 0.003
        truth = robot.transport.truth()  # type: ignore[attr-defined]
        assert abs(truth.true_x_m) < 0.02  # the fake's errors over 1 m
        sent = [c.opcode for c in truth.commands if c.opcode != 128]  # after the Starts
        assert sent[:3] == [150, 131, 148]  # pause an old stream, Safe, the stream


def test_open_with_the_description_settings() -> None:
    settings = RobotSettings("create2", DiffDriveGeometry(508.8, 0.0728, 0.235), True)
    with Create2Robot.open("fakecreate2://?seed=2&time_scale=4", 115200, settings) as robot:
        assert robot.full_mode
        assert robot.geometry.wheel_diameter_m == 0.0728
        robot.arm(DriveSettings(speed_m_s=0.3))
        assert robot.mode() == 3


def test_zero_at_a_given_pose() -> None:
    with Create2Robot.open("fakecreate2://?seed=2&time_scale=4") as robot:
        settings = DriveSettings(speed_m_s=0.3)
        robot.arm(settings)
        sample = robot.zero((1.0, -0.5, 0.3))
        assert (sample.x_m, sample.y_m, sample.theta_rad) == pytest.approx((1.0, -0.5, 0.3))
        robot.drive(Design(0.5, 0.5), settings)
        end = robot.odometry()
        assert end.x_m == pytest.approx(1.0 + 0.5 * 0.9553365, abs=0.003)  # cos 0.3
        assert end.y_m == pytest.approx(-0.5 + 0.5 * 0.2955202, abs=0.003)  # sin 0.3
