"""One place each: angle wrapping and paper units (odohil/units.py), frame
transforms (odohil/science/frames.py), grouping by design
(odohil/science/grouping.py)."""

from __future__ import annotations

import ast
import math
import re
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from odohil import units
from odohil.protocol.nomad import wire_units
from odohil.science import frames
from odohil.science.grouping import by_design
from odohil.science.parameters import NOMAD150, PARAMETER_NAMES
from odohil.science.paths import Design

ROOT = Path(__file__).resolve().parents[2]
angles = st.floats(-1e4, 1e4, allow_nan=False)
poses = st.tuples(st.floats(-50, 50), st.floats(-50, 50), st.floats(-20, 20))


@given(angles)
def test_wrap_angle_is_in_minus_pi_to_pi_and_exact(angle: float) -> None:
    wrapped = units.wrap_angle(angle)
    assert -math.pi < wrapped <= math.pi
    # the same value as IEEE remainder (exact), but for the end chosen at +pi
    reference = math.remainder(angle, 2.0 * math.pi)
    assert wrapped == (math.pi if reference == -math.pi else reference)
    assert units.wrap_angles(np.array([angle]))[0] == wrapped


def test_wrap_angle_ends_and_small_angles() -> None:
    assert units.wrap_angle(math.pi) == math.pi
    assert units.wrap_angle(-math.pi) == math.pi
    assert units.wrap_angle(3.0 * math.pi) == math.pi
    assert units.wrap_angle(1e-300) == 1e-300  # no rounding through +-pi
    assert units.wrap_angle(-1e-17) == -1e-17
    assert list(units.wrap_angles([-math.pi, 0.0, 2.0 * math.pi])) == [math.pi, 0.0, 0.0]


@given(angles, st.floats(-10, 10))
def test_angle_near_puts_an_angle_within_pi_of_the_reference(angle: float, ref: float) -> None:
    near = units.angle_near(angle, ref)
    assert ref - math.pi - 1e-9 < near <= ref + math.pi + 1e-9
    assert math.isclose(math.cos(near), math.cos(angle), abs_tol=1e-9)
    assert math.isclose(math.sin(near), math.sin(angle), abs_tol=1e-9)
    array = units.angle_near(np.array([angle, angle]), ref)
    assert list(array) == [near, near]


def test_circular_mean_across_the_cut() -> None:
    assert units.circular_mean([math.pi - 0.1, -math.pi + 0.1]) == pytest.approx(math.pi)


def test_wire_angles_keep_the_wire_range() -> None:
    assert wire_units.wire_angle_in_turn(-1) == 3599
    assert wire_units.wire_angle_in_turn(3600) == 0
    assert wire_units.wire_angle_difference(10, 3590) == 20
    assert wire_units.wire_angle_difference(0, 1800) == 1800  # (-1800, 1800], as wrap_angle
    assert wire_units.wire_angle_difference(1800, 0) == 1800


def test_paper_units_round_trip_and_match_the_parameters() -> None:
    paper = NOMAD150.to_paper_units()
    for name, si in zip(PARAMETER_NAMES, NOMAD150.as_tuple(), strict=True):
        assert units.parameter_to_paper(name, si) == pytest.approx(paper[name], rel=1e-15)
        assert units.parameter_from_paper(name, paper[name]) == pytest.approx(si, rel=1e-15)
    assert units.parameter_to_paper("E_R", math.radians(1.0)) == pytest.approx(1.0)
    assert units.parameter_to_paper("K_theta", math.radians(1.0) ** 2) == pytest.approx(1.0)


@given(poses, poses)
def test_relative_pose_inverts_compose(a: tuple[float, float, float], b: tuple[float, ...]) -> None:
    c = frames.compose(a, b)
    back = frames.relative_pose(a, c)
    assert np.allclose(back, b, atol=1e-9)
    assert np.allclose(frames.compose(a, frames.inverse_pose(a)), (0.0, 0.0, 0.0), atol=1e-9)


def test_relative_pose_by_hand() -> None:
    # start at (1, 2) facing +y; a point 3 m further along +y and turned by
    # 0.5 rad is 3 m straight ahead in the start frame, turned 0.5 rad
    x, y, theta = frames.relative_pose((1.0, 2.0, math.pi / 2), (1.0, 5.0, math.pi / 2 + 0.5))
    assert (x, y, theta) == pytest.approx((3.0, 0.0, 0.5))
    # headings are not wrapped: a whole turn stays a whole turn
    assert frames.relative_pose((0, 0, 0), (0, 0, 7.0))[2] == 7.0


@given(poses, poses)
def test_relative_pose_jacobians_match_finite_differences(
    a: tuple[float, float, float], b: tuple[float, float, float]
) -> None:
    by_start, by_end = frames.relative_pose_jacobians(a, b)
    step = 1e-6
    for which, jac in ((0, by_start), (1, by_end)):
        for k in range(3):
            lo, hi = [list(a), list(b)], [list(a), list(b)]
            lo[which][k] -= step
            hi[which][k] += step
            numeric = (
                np.array(frames.relative_pose(*hi)) - np.array(frames.relative_pose(*lo))
            ) / (2 * step)
            assert np.allclose(jac[:, k], numeric, atol=1e-5 * (1 + np.abs(numeric).max()))


def test_rotate_points_matches_the_rotation_matrix() -> None:
    points = np.array([[1.0, 0.5], [-0.2, 0.3]])
    thetas = np.array([0.3, -2.0])
    rx, ry = frames.rotate_points(thetas, points)
    for k, theta in enumerate(thetas):
        moved = points @ frames.rotation(float(theta)).T
        assert np.allclose(rx[k], moved[:, 0])
        assert np.allclose(ry[k], moved[:, 1])


def test_by_design_keeps_first_appearance_order() -> None:
    a, b = Design(1, 1.0), Design(2, 1.0)
    items = [(a, 1), (b, 2), (a, 3)]
    grouped = by_design(items, lambda item: item[0])
    assert list(grouped) == [a, b]
    assert grouped[a] == [(a, 1), (a, 3)]


def _calls_and_functions(path: Path) -> list[str]:
    tree = ast.parse(path.read_text())
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.FunctionDef):
            found.append(f"def {node.name}")
        elif isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute):
            found.append(ast.unparse(node.func))
    return found


def test_no_other_module_wraps_angles_or_converts_paper_units() -> None:
    """The conversions live in units.py and frames.py only: nobody else calls
    math.remainder/fmod or np.remainder, wraps with ``(a + pi) % 2 pi - pi``,
    rotates a displacement into a frame by hand, or defines its own to_paper /
    wrap / rotation."""
    banned_calls = {"math.remainder", "np.remainder", "math.fmod", "np.fmod", "np.mod"}
    banned_defs = {"def to_paper", "def from_paper", "def _paper", "def _wrap", "def wrap"}
    banned_defs |= {"def _unwrapped", "def _angle_diff_wire", "def rotation", "def paper_units"}
    offenders = []
    paths = [p for folder in ("odohil", "fakes", "bench") for p in (ROOT / folder).rglob("*.py")]
    for path in sorted(paths):
        if path.name == "units.py" or path.name == "frames.py":
            continue
        for item in _calls_and_functions(path):
            if item in banned_calls or item in banned_defs:
                offenders.append(f"{path.relative_to(ROOT)}: {item}")
        text = path.read_text()
        for pattern in (r"\+ math\.pi\) % ", r"\bc \* dx \+ s \* dy"):
            if re.search(pattern, text):
                offenders.append(f"{path.relative_to(ROOT)}: {pattern}")
    assert offenders == []
