"""odohil/science/odometry_paths.py judges every odometry step's kind with
numpy: the same comparisons of the same floats as the loop over the steps it
replaced (issue 30, big logs), so the same paths."""

from __future__ import annotations

import numpy as np

from odohil.science.odometry_paths import (
    SPIN_RADIUS_M,
    _sample_kinds,
    in_start_frame,
    step_windows,
)


def _loop_kinds(rel: np.ndarray, spin_radius_m: float) -> list[int]:
    """The step kinds as the former loop made them (0 still, 2 in place, +-1)."""
    kinds = []
    for step_ds, step_dtheta, w_ds, w_dtheta in zip(
        *(values.tolist() for values in step_windows(rel)), strict=True
    ):
        if abs(step_ds) <= 1e-12 and abs(step_dtheta) <= 1e-12:
            kinds.append(0)
        elif abs(w_ds) < spin_radius_m * abs(w_dtheta):
            kinds.append(2)
        else:
            kinds.append(1 if w_ds > 0 else -1)
    return kinds


def test_the_step_kinds_are_the_loops() -> None:
    rng = np.random.default_rng(3)
    for _ in range(60):
        n = int(rng.integers(2, 300))
        scale = rng.choice([0.0, 1e-13, 1e-4, 1e-3, 1e-2], size=(1, 3))
        steps = rng.normal(size=(n, 3)) * scale
        steps[rng.random(n) < 0.3] = 0.0
        rel = in_start_frame(np.cumsum(steps, axis=0))
        kinds = _sample_kinds(rel, SPIN_RADIUS_M)
        assert kinds.tolist() == _loop_kinds(rel, SPIN_RADIUS_M)
        assert set(kinds.tolist()) <= {-1, 0, 1, 2}
