"""Planar frame transforms, in one place.

A pose is (x m, y m, theta rad): a frame's origin and heading in another
frame. ``compose(a, b)`` is b (given in a's frame) seen from where a is
given; ``relative_pose(a, c)`` is c seen from a's frame, so that
``compose(a, relative_pose(a, c)) == c``; :func:`relative_pose_jacobians`
gives its derivatives by both poses (covariance propagation). Headings are not wrapped here: a
heading difference keeps the winding the two headings carry (the fake's true
heading and the encoders' both count whole turns), and a caller that wants
it in (-pi, pi] wraps it with :func:`odohil.units.wrap_angle`.

:func:`rotate_points` turns the points of a body by a batch of headings
(the floor-mark model: its Jacobian by the heading is (-ry, rx) of the
rotated points, see :mod:`odohil.science.floor_marks`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from odohil.science.paths import FloatArray

Pose = tuple[float, float, float]
"""(x m, y m, theta rad)."""


def rotation(theta_rad: float) -> FloatArray:
    """The 2x2 rotation matrix of angle theta (radians)."""
    c, s = math.cos(theta_rad), math.sin(theta_rad)
    return np.array([[c, -s], [s, c]], dtype=np.float64)


def _pose(value: Sequence[float] | FloatArray) -> Pose:
    x, y, theta = (float(v) for v in value)
    return (x, y, theta)


def compose(a: Sequence[float] | FloatArray, b: Sequence[float] | FloatArray) -> Pose:
    """``b`` given in the frame of ``a``, expressed where ``a`` is given
    (x m, y m, theta rad; theta_a + theta_b unwrapped)."""
    xa, ya, ta = _pose(a)
    xb, yb, tb = _pose(b)
    c, s = math.cos(ta), math.sin(ta)
    return (xa + c * xb - s * yb, ya + s * xb + c * yb, ta + tb)


def relative_pose(start: Sequence[float] | FloatArray, end: Sequence[float] | FloatArray) -> Pose:
    """``end`` in the frame of ``start``: (x m, y m, theta_end - theta_start
    rad, unwrapped). Both poses are given in one common frame."""
    x0, y0, t0 = _pose(start)
    x1, y1, t1 = _pose(end)
    c, s = math.cos(t0), math.sin(t0)
    dx, dy = x1 - x0, y1 - y0
    return (c * dx + s * dy, -s * dx + c * dy, t1 - t0)


def relative_pose_jacobians(
    start: Sequence[float] | FloatArray, end: Sequence[float] | FloatArray
) -> tuple[FloatArray, FloatArray]:
    """The Jacobians of :func:`relative_pose` by ``start`` and by ``end``,
    each 3x3 (rows: x, y, theta of the relative pose; columns: x, y, theta of
    the pose differentiated), to propagate two poses' covariances:
    ``cov = J0 C_start J0^T + J1 C_end J1^T``. With c, s = cos, sin of the
    start heading and (dx, dy) the relative position:
    J0 = [[-c, -s, dy], [s, -c, -dx], [0, 0, -1]], J1 = [[c, s, 0], [-s, c, 0], [0, 0, 1]].
    """
    dx, dy, _ = relative_pose(start, end)
    theta0 = float(_pose(start)[2])
    c, s = math.cos(theta0), math.sin(theta0)
    by_start = np.array([[-c, -s, dy], [s, -c, -dx], [0.0, 0.0, -1.0]], dtype=np.float64)
    by_end = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]], dtype=np.float64)
    return by_start, by_end


def inverse_pose(pose: Sequence[float] | FloatArray) -> FloatArray:
    """The inverse rigid motion of (dx m, dy m, dtheta rad), same units: the
    origin seen from ``pose``'s frame."""
    return np.array(relative_pose(pose, (0.0, 0.0, 0.0)), dtype=np.float64)


def rotate_points(theta_rad: FloatArray, points: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Points (m, 2) of a body rotated by each heading of ``theta_rad`` (B,):
    the x and y parts, each (B, m), in the points' units."""
    c = np.cos(theta_rad)[:, None]
    s = np.sin(theta_rad)[:, None]
    px, py = points[:, 0], points[:, 1]
    return c * px - s * py, s * px + c * py
