"""Robot description: parsing the TOML format and rejecting bad descriptions."""

from __future__ import annotations

from pathlib import Path

import pytest

from odohil.errors import InitError, RobotDescriptionError
from odohil.science.robot_description import (
    ParameterPriors,
    RobotDescription,
    Screw,
    SerialSettings,
)
from odohil.session.robots.description import load_robot_description
from odohil.session.robots.registry import parse_description as parse_robot_description

EXAMPLE = """
[screws]                 # positions in the robot frame (x forward, y left), metres
A = [0.20, 0.0]
B = [-0.10, 0.173]
C = [-0.10, -0.173]
[measurement]
sigma_m = 0.001          # standard deviation of one tape reading, metres
cross = [["A", "B"], ["B", "C"]]  # start mark of A to end mark of B, B to C
[serial]                 # optional, for the driver
port = "/dev/ttyUSB0"    # or any pyserial URL
baud = 38400             # 4800, 9600, 19200 or 38400
timeout_s = 1.0
[priors]                 # optional: the parameters before any trial (paper units)
E_R_deg_per_m = -0.202   # defaults: the paper's Nomad 150 values ...
E_R_sd_deg_per_m = 0.5   # ... and these spreads (one standard deviation)
E_T = -0.02
E_T_sd = 0.05
K_theta_deg2_per_m = 0.012
K_theta_sd_deg2_per_m = 0.05
K_rho_m = 3.6e-5
K_rho_sd_m = 2e-4
"""

MINIMAL = """
[screws]
A = [0.20, 0.0]
B = [-0.10, 0.173]
C = [-0.10, -0.173]
[measurement]
sigma_m = 0.001
"""


def test_example_parses_to_the_documented_values() -> None:
    description = parse_robot_description(EXAMPLE)
    assert description.screws == (
        Screw("A", 0.20, 0.0),
        Screw("B", -0.10, 0.173),
        Screw("C", -0.10, -0.173),
    )
    assert description.sigma_m == 0.001
    assert description.cross_pairs == (("A", "B"), ("B", "C"))
    assert description.serial == SerialSettings(port="/dev/ttyUSB0", baud=38400, timeout_s=1.0)
    assert description.cross_indices() == ((0, 1), (1, 2))
    assert description.priors == ParameterPriors(given=True)  # the documented defaults
    assert description.positions().shape == (3, 2)


def test_an_empty_priors_table_says_the_robot_is_the_papers_nomad() -> None:
    """``[priors]`` with no keys is the paper's Nomad 150, said of this robot;
    without the table the slip check predicts for any robot (issue 31)."""
    assert parse_robot_description(MINIMAL + "[priors]\n").priors == ParameterPriors(given=True)
    assert parse_robot_description(MINIMAL).priors == ParameterPriors(given=False)


def test_example_in_the_docs_is_the_tested_one() -> None:
    docs = Path(__file__).resolve().parents[2] / "docs" / "measurements.md"
    assert EXAMPLE.strip() in docs.read_text()


def test_optional_parts_take_defaults_and_screws_keep_file_order() -> None:
    text = MINIMAL.replace("A = [0.20, 0.0]\n", "").replace(
        "[measurement]", "Z = [0.2, 0]\n[measurement]"
    )
    description = parse_robot_description(text)
    assert description.screw_names == ("B", "C", "Z")
    assert description.cross_pairs == ()
    assert description.serial == SerialSettings(port=None, baud=38400, timeout_s=1.0)


def test_integers_are_accepted_as_metres() -> None:
    description = parse_robot_description(MINIMAL.replace("[0.20, 0.0]", "[1, 0]"))
    assert description.screws[0] == Screw("A", 1.0, 0.0)


def test_loading_from_a_file(tmp_path: Path) -> None:
    path = tmp_path / "robot.toml"
    path.write_text(EXAMPLE, encoding="utf-8")
    assert load_robot_description(path) == parse_robot_description(EXAMPLE)


def test_a_missing_file_is_a_robot_description_error(tmp_path: Path) -> None:
    with pytest.raises(RobotDescriptionError, match="cannot read"):
        load_robot_description(tmp_path / "absent.toml")


def test_errors_from_a_file_name_the_file(tmp_path: Path) -> None:
    path = tmp_path / "robot.toml"
    path.write_text(MINIMAL.replace("0.001", "-1"), encoding="utf-8")
    with pytest.raises(RobotDescriptionError, match=r"robot\.toml.*sigma_m"):
        load_robot_description(path)


@pytest.mark.parametrize(
    ("old", "new", "message"),
    [
        ("C = [-0.10, -0.173]\n", "", r"at least three screws"),
        ("C = [-0.10, -0.173]", "C = [0.2, 0.005]", r"A and screws\.C coincide"),
        ("C = [-0.10, -0.173]", "C = [0.5, -0.173]", r"collinear"),
        (
            "B = [-0.10, 0.173]\nC = [-0.10, -0.173]",
            "B = [-0.10, 0.01]\nC = [0.05, 0.005]\nD = [0.1, -0.003]",
            r"collinear",
        ),
        ("sigma_m = 0.001", "sigma_m = 0.001\nsigma = 2", r"unknown key.*measurement\.sigma"),
        ("[measurement]", "colour = 'red'\n[measurement]", r"screws\.colour must be \[x, y\]"),
        ("[screws]", "[robot]\nname = 'n150'\n[screws]", r"unknown key.*robot"),
        ("sigma_m = 0.001", "sigma_m = 0.001\n[serial]\nspeed = 9600", r"serial\.speed"),
        ("A = [0.20, 0.0]", "A = [0.20, '0.0']", r"screws\.A\[1\] must be a number"),
        ("A = [0.20, 0.0]", "A = [true, 0.0]", r"screws\.A\[0\] must be a number"),
        ("A = [0.20, 0.0]", "A = [0.20, nan]", r"screws\.A\[1\] must be a finite"),
        ("A = [0.20, 0.0]", "A = [0.20]", r"screws\.A must be \[x, y\]"),
        ("sigma_m = 0.001", "sigma_m = '1 mm'", r"measurement\.sigma_m must be a number"),
        ("sigma_m = 0.001", "sigma_m = 0", r"sigma_m must be a positive"),
        ("sigma_m = 0.001", "sigma_m = -0.001", r"sigma_m must be a positive"),
        ("sigma_m = 0.001\n", "", r"measurement\.sigma_m is missing"),
        ("sigma_m = 0.001", "sigma_m = 0.001\ncross = [['A', 'Q']]", r"unknown screw 'Q'"),
        ("sigma_m = 0.001", "sigma_m = 0.001\ncross = [['B', 'B']]", r"screw 'B' twice"),
        (
            "sigma_m = 0.001",
            "sigma_m = 0.001\ncross = [['A', 'B'], ['B', 'C'], ['C', 'A']]",
            r"at most 2 cross",
        ),
        ("sigma_m = 0.001", "sigma_m = 0.001\ncross = [['A', 'B'], ['A', 'B']]", r"twice"),
        ("sigma_m = 0.001", "sigma_m = 0.001\ncross = [['A']]", r"cross\[0\] must be a pair"),
        ("sigma_m = 0.001", "sigma_m = 0.001\ncross = 'AB'", r"cross must be a list"),
        ("sigma_m = 0.001", "sigma_m = 0.001\n[serial]\nbaud = 115200", r"serial\.baud"),
        ("sigma_m = 0.001", "sigma_m = 0.001\n[serial]\nbaud = 9600.0", r"serial\.baud"),
        ("sigma_m = 0.001", "sigma_m = 0.001\n[serial]\ntimeout_s = 0", r"serial\.timeout_s"),
        ("sigma_m = 0.001", "sigma_m = 0.001\n[serial]\nport = 3", r"serial\.port"),
        ("[measurement]\nsigma_m = 0.001\n", "", r"\[measurement\] table is missing"),
        (
            "[screws]\nA = [0.20, 0.0]\nB = [-0.10, 0.173]\nC = [-0.10, -0.173]\n",
            "screws = 3\n",
            r"screws must be a table",
        ),
        ("[screws]", "[screws", r"not valid TOML"),
    ],
)
def test_invalid_descriptions_name_the_key_and_the_problem(
    old: str, new: str, message: str
) -> None:
    assert old in MINIMAL
    with pytest.raises(RobotDescriptionError, match=message):
        parse_robot_description(MINIMAL.replace(old, new))


def test_robot_description_errors_are_init_errors() -> None:
    with pytest.raises(InitError):
        parse_robot_description("")


def test_the_dataclass_validates_when_built_directly() -> None:
    screws = (Screw("A", 0.0, 0.0), Screw("B", 1.0, 0.0), Screw("C", 0.0, 1.0))
    RobotDescription(screws, sigma_m=0.001)
    with pytest.raises(RobotDescriptionError, match="sigma_m"):
        RobotDescription(screws, sigma_m=float("nan"))
    with pytest.raises(RobotDescriptionError, match="unique"):
        RobotDescription((*screws[:2], Screw("A", 0.0, 1.0)), sigma_m=0.001)


def test_pose_sigma_for_motion_capture_is_optional_and_parsed() -> None:
    assert parse_robot_description(MINIMAL).pose_sigma is None
    text = MINIMAL + "pose_sigma = [0.0005, 0.0007, 0.001]\n"
    assert parse_robot_description(text).pose_sigma == (0.0005, 0.0007, 0.001)


@pytest.mark.parametrize(
    ("value", "message"),
    [
        ("0.001", r"measurement\.pose_sigma must be \[sigma_x_m, sigma_y_m, sigma_theta_rad\]"),
        ("[0.001, 0.001]", r"pose_sigma must be \[sigma_x_m"),
        ("[0.001, '1 mm', 0.001]", r"measurement\.pose_sigma\[1\] must be a number"),
        ("[0.001, 0.001, nan]", r"measurement\.pose_sigma\[2\] must be a finite"),
        (
            "[0, 0.001, 0.001]",
            r"pose_sigma\[0\] \(sigma_x_m\) must be at least 1e-06 and at most 1 m",
        ),
        ("[0.001, -1, 0.001]", r"pose_sigma\[1\] \(sigma_y_m\) must be at least 1e-06"),
        ("[0.001, 0.001, 2.0]", r"pose_sigma\[2\] \(sigma_theta_rad\) must be .* at most 1 rad"),
    ],
)
def test_bad_pose_sigma_names_the_key_and_the_range(value: str, message: str) -> None:
    with pytest.raises(RobotDescriptionError, match=message):
        parse_robot_description(MINIMAL + f"pose_sigma = {value}\n")


def test_the_still_window_for_motion_capture_is_optional_parsed_and_bounded() -> None:
    from odohil.session.measure.mocap import StillCriteria, still_criteria_of

    plain = parse_robot_description(MINIMAL)
    assert plain.still_window_s is None
    assert still_criteria_of(plain) == StillCriteria()  # the default window, 0.5 s
    short = parse_robot_description(MINIMAL + "still_window_s = 0.15\n")
    assert short.still_window_s == 0.15
    assert still_criteria_of(short) == StillCriteria(window_s=0.15)
    for value, message in (
        ("0", r"measurement\.still_window_s must be at least 0\.02 and at most 60 s"),
        ("61", r"measurement\.still_window_s must be at least 0\.02 and at most 60 s"),
        ("'1 s'", r"measurement\.still_window_s must be a number"),
    ):
        with pytest.raises(RobotDescriptionError, match=message):
            parse_robot_description(MINIMAL + f"still_window_s = {value}\n")
