"""The fake's one-segment step (fakes/nomad/segment.py) is the simulator's
discrete model, draw for draw: the science layer keeps one implementation and
no special path for the fake."""

from __future__ import annotations

import numpy as np
import pytest

from fakes.nomad.draws import ziggurat_tables
from fakes.nomad.segment import drive_segment, drive_segments
from odohil.science.parameters import NOMAD150, ErrorParameters
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


QUIET_TRANSLATION = ErrorParameters.from_paper_units(-0.2, 0.01, 0.02, 0.0)


@pytest.mark.parametrize(
    "params", [LOUD, NOMAD150, QUIET_TRANSLATION], ids=["loud", "nomad150", "k_rho_0"]
)
@pytest.mark.parametrize("segment_m", [0.001, -0.02, 0.0007])
def test_many_segments_at_once_are_the_one_by_one_segments_to_the_last_bit(
    params: ErrorParameters, segment_m: float
) -> None:
    # the bulk path is the one under test: this numpy's draws are followed
    assert ziggurat_tables() is not None
    for seed in range(6):
        for n in (1, 5, 40, 300, 2000):  # 2000 segments meet numpy's rarer draws
            one_rng, bulk_rng = make_rng(seed), make_rng(seed)
            start = (0.1, -0.2, 2.0)
            pose = start
            for _ in range(n):
                pose = drive_segment(pose, segment_m, params, one_rng)
            assert drive_segments(start, segment_m, n, params, bulk_rng) == pose
            # the generator is left at the same place in its stream
            assert bulk_rng.random(4).tolist() == one_rng.random(4).tolist()
