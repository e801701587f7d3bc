"""A trial's pose change from two world poses, and its covariance.

The start pose P0 = (x0, y0, theta0) and end pose P1 are measured in the
capture system's world frame, each with its own covariance (x, y along the
world axes, theta). The pose change is P1 in P0's frame:

    d = R(theta0)^T (p1 - p0),   dtheta = wrap(theta1 - theta0)

First-order propagation (c, s = cos theta0, sin theta0; d = (dx, dy)):

    J0 = d(change)/d(P0) = [[-c, -s,  dy],
                            [ s, -c, -dx],
                            [ 0,  0,  -1]]
    J1 = d(change)/d(P1) = [[ c,  s,   0],
                            [-s,  c,   0],
                            [ 0,  0,   1]]
    cov(change) = J0 C0 J0^T + J1 C1 J1^T

(d(R^T)/d(theta0) (p1 - p0) = (dy, -dx).) The transform and both Jacobians
are odohil/science/frames.py's (``relative_pose``, ``relative_pose_jacobians``).
The neglected terms are of order
sigma_theta^2 |d| and sigma_theta sigma_xy; tests/session/test_mocap_change.py
checks the formula against a Monte Carlo of the transform itself.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import numpy.typing as npt

from odohil.science import frames
from odohil.units import wrap_angle

FloatArray = npt.NDArray[np.float64]


def pose_change_with_covariance(
    start: Sequence[float],
    end: Sequence[float],
    start_cov: npt.ArrayLike,
    end_cov: npt.ArrayLike,
) -> tuple[tuple[float, float, float], FloatArray]:
    """The end pose in the start pose's frame, and its 3x3 covariance.

    Args:
        start, end: world poses (x m, y m, theta rad).
        start_cov, end_cov: their 3x3 covariances (m^2, m^2, rad^2 on the
            diagonal), world axes.

    Returns:
        ((dx m, dy m, dtheta rad in (-pi, pi]), covariance).
    """
    dx, dy, turned = frames.relative_pose(start, end)
    change = (dx, dy, wrap_angle(turned))
    j0, j1 = frames.relative_pose_jacobians(start, end)
    c0 = np.asarray(start_cov, dtype=np.float64)
    c1 = np.asarray(end_cov, dtype=np.float64)
    cov = j0 @ c0 @ j0.T + j1 @ c1 @ j1.T
    return change, 0.5 * (cov + cov.T)
