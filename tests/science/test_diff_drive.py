"""The differential drive's wheel errors map onto E_R, E_T, K_theta and K_rho
as odohil/science/diff_drive.py says: checked against an integration of the
two wheels written here from the kinematics alone (no odohil code)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from odohil.errors import ParameterError
from odohil.protocol.create2.geometry import CREATE2_GEOMETRY
from odohil.science.diff_drive import (
    DiffDriveErrors,
    DiffDriveGeometry,
    odometry_step,
    simulate_diff_drive,
)
from odohil.science.parameters import ErrorParameters
from odohil.science.paths import Design, EncoderPath, Leg, Turn

B = CREATE2_GEOMETRY.wheel_base_m


def wheels(
    path: EncoderPath,
    e_l: float,
    e_r: float,
    e_b: float,
    k_wheel: float,
    n: int,
    rng: np.random.Generator,
    step_m: float = 0.002,
) -> np.ndarray:
    """End poses of n trials, integrating the true wheel travels in small steps.

    Each wheel's true travel is its encoder travel times (1 + e) plus
    N(0, k_wheel |encoder travel|), independently; the pose follows the arc
    of the two travels with the true wheel base.
    """
    base = B * (1.0 + e_b)
    x, y, th = np.zeros(n), np.zeros(n), np.zeros(n)
    for step in path.steps:
        if isinstance(step, Leg):
            enc_l = enc_r = step.length_m
        else:
            enc_r = 0.5 * B * step.angle_rad
            enc_l = -enc_r
        m = max(1, math.ceil(max(abs(enc_l), abs(enc_r)) / step_m))
        for _ in range(m):
            dl = enc_l / m * (1 + e_l) + rng.standard_normal(n) * math.sqrt(
                k_wheel * abs(enc_l) / m
            )
            dr = enc_r / m * (1 + e_r) + rng.standard_normal(n) * math.sqrt(
                k_wheel * abs(enc_r) / m
            )
            d, dth = 0.5 * (dl + dr), (dr - dl) / base
            mid = th + 0.5 * dth
            chord = d * np.sinc(dth / (2 * math.pi))
            x += chord * np.cos(mid)
            y += chord * np.sin(mid)
            th += dth
    th -= path.winding_rad
    return np.stack([x, y, th], axis=1)


ERRORS = {"e_l": 0.012, "e_r": -0.008, "e_b": 0.03}


@pytest.mark.parametrize(
    "design", [Design(0.5, 2.0), Design(2, 1.0, "reverse"), Design(2, 1.0, "turn")]
)
def test_noise_free_wheels_match_the_mapped_model(design: Design) -> None:
    errors = DiffDriveErrors(
        wheel_base_m=B,
        left_scale=ERRORS["e_l"],
        right_scale=ERRORS["e_r"],
        base_scale=ERRORS["e_b"],
    )
    seg = 0.0005
    rng = np.random.default_rng(0)
    want = wheels(design.path(), **ERRORS, k_wheel=0.0, n=1, rng=rng, step_m=seg)[0]
    got = simulate_diff_drive(design.path(), errors, 1, seed=0, segment_m=seg).pose_change[0]
    # the paper's discrete model turns before it translates each segment: O(E_R seg) apart
    tolerance = abs(errors.straight_parameters().e_r) * seg * design.distance_m
    assert np.allclose(got, want, rtol=0, atol=tolerance), (got, want, tolerance)


def test_mapping_formulas() -> None:
    errors = DiffDriveErrors(wheel_base_m=B, left_scale=0.01, right_scale=0.03, base_scale=0.05)
    params = errors.straight_parameters()
    assert params.e_t == pytest.approx(0.02)
    assert params.e_r == pytest.approx(0.02 / (B * 1.05))
    assert errors.turn_scale == pytest.approx(1.02 / 1.05 - 1)
    back = DiffDriveErrors.from_parameters(params, turn_scale=errors.turn_scale, wheel_base_m=B)
    assert back.left_scale == pytest.approx(0.01)
    assert back.right_scale == pytest.approx(0.03)
    assert back.base_scale == pytest.approx(0.05)


@pytest.mark.parametrize("design", [Design(1, 2.0, "reverse"), Design(1, 1.0, "turn")])
def test_wheel_slip_maps_onto_k_theta_and_k_rho_monte_carlo(design: Design) -> None:
    """Independent wheel slip k_w per metre is K_rho = k_w/2 and K_theta =
    2 k_w / b_true^2: means and variances agree within 4 Monte Carlo SE."""
    k_wheel = 4e-5
    base = B * (1 + ERRORS["e_b"])
    n = 4000
    errors = DiffDriveErrors(
        wheel_base_m=B,
        left_scale=ERRORS["e_l"],
        right_scale=ERRORS["e_r"],
        base_scale=ERRORS["e_b"],
        k_theta=2 * k_wheel / base**2,
        k_rho=k_wheel / 2,
        # a spin of angle a drives each wheel b a / 2: heading variance
        # 2 k_w (b a / 2) / b_true^2 per spin
        k_spin=k_wheel * B / base**2,
    )
    rng = np.random.default_rng(12)
    ref = wheels(design.path(), **ERRORS, k_wheel=k_wheel, n=n, rng=rng, step_m=0.01)
    got = simulate_diff_drive(design.path(), errors, n, seed=rng, segment_m=0.01).pose_change
    for j in range(3):
        a, b = ref[:, j], got[:, j]
        se_mean = math.sqrt(a.var() / n + b.var() / n)
        assert abs(a.mean() - b.mean()) < 4 * se_mean + 1e-9, (j, a.mean(), b.mean())
        # SE of a sample variance is about var sqrt(2/n) for near-Gaussian data
        se_var = math.sqrt(2 / n) * math.hypot(a.var(), b.var())
        assert abs(a.var() - b.var()) < 4 * se_var + 1e-12, (j, a.var(), b.var())


def test_odometry_step_is_the_facts_documents_worked_example() -> None:
    geometry = CREATE2_GEOMETRY  # the Create 2's nominal constants
    left, right = geometry.wheel_travel(1000, 1010)
    assert left * 1000 == pytest.approx(444.565, abs=1e-3)
    assert right * 1000 == pytest.approx(449.011, abs=1e-3)
    x, y, th = odometry_step((0.0, 0.0, 0.0), left, right, geometry.wheel_base_m)
    assert th == pytest.approx(0.018918, abs=1e-6)
    assert x * 1000 == pytest.approx(446.761, abs=1e-3)
    assert y * 1000 == pytest.approx(4.226, abs=1e-3)
    assert geometry.counts_for(2.0) == pytest.approx(4498.8, abs=0.1)


def test_spin_error_scales_with_the_angle() -> None:
    errors = DiffDriveErrors(wheel_base_m=B, base_scale=0.02)
    for turns in (1, 4):
        path = EncoderPath((Leg(0.1), Turn(turns * math.pi), Leg(0.1)))
        pose = simulate_diff_drive(path, errors, 1, seed=0).pose_change[0]
        want = turns * math.pi * (1 / 1.02 - 1)
        assert pose[2] - (turns * math.pi - path.winding_rad) == pytest.approx(want, rel=1e-9)


def test_bad_values_are_refused() -> None:
    with pytest.raises(ParameterError, match="left_scale"):
        DiffDriveErrors(wheel_base_m=B, left_scale=-1.5)
    with pytest.raises(ParameterError, match="k_spin"):
        DiffDriveErrors(wheel_base_m=B, k_spin=-1.0)
    with pytest.raises(ParameterError, match="wheel_base_m"):
        DiffDriveGeometry(508.8, 0.072, wheel_base_m=0.0)
    assert isinstance(DiffDriveErrors(wheel_base_m=B).straight_parameters(), ErrorParameters)
