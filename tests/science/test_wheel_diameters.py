"""``[robot] wheel_diameter_m`` may give the two wheels apart ([left, right]):
parsed, checked by index, and used per wheel."""

from __future__ import annotations

import math

import pytest

from odohil.errors import RobotDescriptionError
from odohil.protocol.create2.geometry import CREATE2_GEOMETRY
from odohil.session.robots.registry import parse_description as parse_robot_description

BASE = """
[screws]
A = [0.1, 0.0]
B = [-0.05, 0.08]
C = [-0.05, -0.08]
[measurement]
sigma_m = 0.001
[robot]
protocol = "create2"
"""


def test_two_diameters_are_the_left_and_the_right_wheel() -> None:
    drive = parse_robot_description(BASE + "wheel_diameter_m = [0.0720, 0.0724]\n").robot.drive
    assert drive.wheel_diameters_m == (0.0720, 0.0724)
    left, right = drive.wheel_metres_per_count
    assert math.isclose(left, math.pi * 0.0720 / 508.8)
    assert math.isclose(right, math.pi * 0.0724 / 508.8)
    assert drive.wheel_travel(100, 100) == (100 * left, 100 * right)
    assert math.isclose(drive.metres_per_count, 0.5 * (left + right))


def test_one_diameter_serves_both_wheels_as_before() -> None:
    drive = parse_robot_description(BASE + "wheel_diameter_m = 0.072\n").robot.drive
    assert drive == CREATE2_GEOMETRY  # the backend's nominal constants, one diameter given
    assert drive.wheel_diameters_m == (0.072, 0.072)


@pytest.mark.parametrize(
    ("value", "message"),
    [
        ("[0.072]", r"robot.wheel_diameter_m must be one number or \[left, right\]"),
        ("[0.072, 3.0]", r"robot.wheel_diameter_m\[1\] must be in \[0.005, 2\], got 3.0"),
        ('[0.072, "x"]', r"robot.wheel_diameter_m\[1\] must be a number"),
    ],
)
def test_bad_diameters_name_the_key_and_the_index(value: str, message: str) -> None:
    with pytest.raises(RobotDescriptionError, match=message):
        parse_robot_description(BASE + f"wheel_diameter_m = {value}\n")
