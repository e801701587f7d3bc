"""The fake's one-segment step (fakes/nomad/segment.py) is the simulator's
discrete model, draw for draw: the science layer keeps one implementation and
no special path for the fake."""

from __future__ import annotations

import numpy as np
import pytest

from fakes.nomad.segment import drive_segment
from odohil.science.parameters import ErrorParameters
from odohil.science.simulator import drive_straight, make_rng

LOUD = ErrorParameters.from_paper_units(20.0, -0.05, 50.0, 1e-3)


@pytest.mark.parametrize("segment_m", [-0.02, 0.001, 0.0007])
def test_one_segment_steps_match_the_simulator_draw_for_draw(segment_m: float) -> None:
    for seed in range(20):
        rng_fake, rng_sim = make_rng(seed), make_rng(seed)
        pose = (0.1, -0.2, 2.0)
        x, y, theta = np.array([0.1]), np.array([-0.2]), np.array([2.0])
        for _ in range(50):
            pose = drive_segment(pose, segment_m, LOUD, rng_fake)
            drive_straight(x, y, theta, segment_m, 1, LOUD, rng_sim)
        np.testing.assert_allclose(pose, [x[0], y[0], theta[0]], rtol=0, atol=1e-5)
        assert rng_fake.random() == rng_sim.random()  # the same number of draws


def test_a_seed_gives_the_same_poses() -> None:
    def run(seed: int) -> tuple[float, float, float]:
        rng, pose = make_rng(seed), (0.0, 0.0, 0.0)
        for _ in range(500):
            pose = drive_segment(pose, 0.001, LOUD, rng)
        return pose

    assert run(3) == run(3)
    assert run(3) != run(4)
