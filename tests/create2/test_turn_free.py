"""Why a differential drive is calibrated with turn-free designs: on the fake
Create 2's physics, the paper's ``turn`` variant biases E_R or K_theta by more
than 4 standard errors; the ``reverse`` variant does not.

The fake's body (fakes/create2/body.py) and the batch simulator
(odohil/science/diff_drive.py) share one physics; the first test checks that
the body, driven tick by tick as over the wire, gives the simulator's
distribution, so the fast simulator stands in for the pty here."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fakes.create2.body import Create2Body
from fakes.create2.config import Create2Config
from odohil.science.diff_drive import simulate_diff_drive
from odohil.science.estimators import Observation, estimate
from odohil.science.paths import Design, Leg

CONFIG = Create2Config()
ERRORS = CONFIG.errors
TRUTH = ERRORS.straight_parameters()
TICK_S = 0.015
MEAS = np.diag([1e-6, 1e-6, math.radians(0.2) ** 2])
"""Measurement covariance of a pose (1 mm, 0.2 degree)."""


def body_trial(design: Design, rng: np.random.Generator, speed_mm_s: float = 300.0) -> np.ndarray:
    """One trial of ``design`` on the fake's body, commanded as the driver does:
    wheel speeds for whole ticks, the last tick cut at the step's end."""
    body = Create2Body(ERRORS, CONFIG.geometry, rng, segment_m=0.01)
    half_base_mm = CONFIG.geometry.wheel_base_m * 500.0
    for step in design.path().steps:
        if isinstance(step, Leg):
            sign = 1.0 if step.length_m > 0 else -1.0
            signs, travel_mm = (sign, sign), abs(step.length_m) * 1000.0
        else:
            sign = 1.0 if step.angle_rad > 0 else -1.0
            signs, travel_mm = (-sign, sign), abs(step.angle_rad) * half_base_mm
        body.set_wheels(signs[1] * speed_mm_s, signs[0] * speed_mm_s)
        duration = travel_mm / speed_mm_s
        end = body.t + duration
        while body.t < end - 1e-12:
            body.advance(min(end, body.t + TICK_S))
        body.stop()
    x, y, theta = body.true_pose()
    return np.array([x, y, theta - design.path().winding_rad])


@pytest.mark.parametrize("design", [Design(1, 1.0, "turn"), Design(1, 1.0, "reverse")])
def test_the_fake_body_gives_the_simulators_distribution(design: Design) -> None:
    n = 300
    rng = np.random.default_rng(31)
    body = np.array([body_trial(design, rng) for _ in range(n)])
    sim = simulate_diff_drive(design.path(), ERRORS, 4000, seed=rng, segment_m=0.01).pose_change
    for j in range(3):
        se = math.sqrt(body[:, j].var() / n + sim[:, j].var() / sim.shape[0])
        assert abs(body[:, j].mean() - sim[:, j].mean()) < 4 * se, j
        se_var = math.sqrt(2 / n) * body[:, j].var() + math.sqrt(2 / 4000) * sim[:, j].var()
        assert abs(body[:, j].var() - sim[:, j].var()) < 4 * se_var, j


def estimate_plan(variant: str, seed: int) -> dict[str, float]:
    """z-scores (estimate - truth) / stderr of a three-design plan of ``variant``."""
    rng = np.random.default_rng(seed)
    observations = []
    for design, n in (
        (Design(0.5, 3.0, variant), 40),  # type: ignore[arg-type]
        (Design(1, 3.0, variant), 40),  # type: ignore[arg-type]
        (Design(5, 1.0, variant), 40),  # type: ignore[arg-type]
    ):
        poses = simulate_diff_drive(design.path(), ERRORS, n, seed=rng, segment_m=0.01)
        noisy = poses.pose_change + rng.multivariate_normal(np.zeros(3), MEAS, size=n)
        observations += [Observation(design, p, MEAS) for p in noisy]
    result = estimate(observations)
    return {
        p.name: (p.value - true) / p.stderr
        for p, true in zip(result.parameters, TRUTH.as_tuple(), strict=True)
    }


@pytest.mark.parametrize("seed", [1, 2])
def test_turn_variant_biases_e_r_or_k_theta_reverse_does_not(seed: int) -> None:
    turn = estimate_plan("turn", seed)
    reverse = estimate_plan("reverse", seed)
    assert max(abs(turn["E_R"]), abs(turn["K_theta"])) > 4, turn
    assert all(abs(z) < 4 for z in reverse.values()), reverse
