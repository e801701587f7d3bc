"""The TRUE pose drifts as the four parameters say (in process, many runs, 4-SE tolerances)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from fakes.nomad.body import RobotBody
from odohil.protocol.nomad import messages as m
from odohil.protocol.nomad import wire_units
from odohil.science.parameters import ErrorParameters

from .link import RawLink

# Exaggerated values so that few runs give a sharp test (paper units).
E_R_DEG, E_T, K_THETA_DEG2, K_RHO = 5.0, 0.05, 1.0, 1e-4
PARAMS = ErrorParameters.from_paper_units(E_R_DEG, E_T, K_THETA_DEG2, K_RHO)
RUNS = 300
WIRE = 394  # one metre, rounded to the wire unit


def _runs(fake_port: Any, steer: int) -> tuple[np.ndarray, np.ndarray, float]:
    """Heading changes (rad) and chord lengths (m) of RUNS straight runs of WIRE units,
    and the true heading (rad) after the initial in-place turn by ``steer``."""
    port = fake_port(
        f"seed=11&time_scale=10000&E_R={E_R_DEG}&E_T={E_T}&K_theta={K_THETA_DEG2}&K_rho={K_RHO}"
    )
    link = RawLink(port)
    link.request(m.Sp(200, 450, 450))
    if steer:
        link.request(m.Pr(0, steer, 0))
        link.request(m.Ws(True, True, True, 5))
    heading0 = port.truth().true_theta_rad
    turns, chords = [], []
    for _ in range(RUNS):
        before = port.truth()
        link.request(m.Dp(0, 0))
        link.request(m.Pr(WIRE, 0, 0))
        link.request(m.Ws(True, True, True, 5))
        after = port.truth()
        assert not after.moving
        assert (after.encoder_x, after.encoder_y) == (
            round(WIRE * math.cos(math.radians(steer / 10))),
            round(WIRE * math.sin(math.radians(steer / 10))),
        )
        turns.append(after.true_theta_rad - before.true_theta_rad)
        chords.append(
            math.hypot(after.true_x_m - before.true_x_m, after.true_y_m - before.true_y_m)
        )
    return np.array(turns), np.array(chords), heading0


def test_heading_and_distance_drift_match_the_parameters(fake_port: Any) -> None:
    d = wire_units.wire_to_metres(WIRE)
    turns, chords, _ = _runs(fake_port, steer=0)
    n = len(turns)

    mean_turn = PARAMS.e_r * d  # eq. 2, per metre driven
    var_turn = PARAMS.k_theta * d  # eq. 11
    se_mean = math.sqrt(var_turn / n)
    assert abs(turns.mean() - mean_turn) < 4 * se_mean
    se_var = var_turn * math.sqrt(2.0 / (n - 1))
    assert abs(turns.var(ddof=1) - var_turn) < 4 * se_var

    # chord of an arc of length (1 + E_T) d turning by E_R d
    half = mean_turn / 2
    mean_chord = (1 + PARAMS.e_t) * d * math.sin(half) / half
    var_chord = PARAMS.k_rho * d  # eq. 14 (heading noise adds O(K_theta^2), negligible)
    assert abs(chords.mean() - mean_chord) < 4 * math.sqrt(var_chord / n)
    assert abs(chords.var(ddof=1) - var_chord) < 4 * var_chord * math.sqrt(2.0 / (n - 1))


def test_steering_turns_are_error_free_and_drive_follows_them(fake_port: Any) -> None:
    turns, _, heading0 = _runs(fake_port, steer=900)
    assert abs(heading0 - math.pi / 2) < 1e-12  # in-place turns are error free
    # the 90 deg turn happened before the runs: each run drifts as on the x axis
    se_mean = math.sqrt(PARAMS.k_theta * wire_units.wire_to_metres(WIRE) / len(turns))
    assert abs(turns.mean() - PARAMS.e_r * wire_units.wire_to_metres(WIRE)) < 4 * se_mean


def test_a_seed_fixes_the_true_pose_whatever_the_clock(fake_port: Any) -> None:
    """The same motion at two time scales is sliced into different wall-clock
    steps; the true end pose must not depend on that (reproducible demos)."""
    ends = []
    for time_scale in (20, 5000):
        port = fake_port(f"seed=4&time_scale={time_scale}&E_R=20&K_theta=50&K_rho=1e-3")
        link = RawLink(port)
        link.request(m.Sp(200, 450, 450))
        for move in (m.Pr(300, 0, 0), m.Pr(0, 1800, 0), m.Pr(300, 0, 0)):
            link.request(move)
            link.request(m.Ws(True, True, True, 30))
        truth = port.truth()
        ends.append((truth.true_x_m, truth.true_y_m, truth.true_theta_rad))
    # with these parameters two independent draws would differ by centimetres
    assert np.allclose(ends[0], ends[1], rtol=0.0, atol=1e-12), ends


def _two_legs_of_762_segments(start_s: float, cuts_s: tuple[float, ...]) -> tuple[float, ...]:
    """True end pose after two 300-wire runs (762.0 segments of 1 mm each) with a
    180 degree turn between them, the physics advanced first to ``start_s`` and then
    in steps of ``cuts_s`` per move."""
    params = ErrorParameters.from_paper_units(20.0, 0.0, 50.0, 1e-3)
    body = RobotBody(params, np.random.default_rng(4))
    body.set_speeds((200, 450, 450))
    body.advance(start_s)
    for move in ((300, 0, 0), (0, 1800, 0), (300, 0, 0)):
        body.move_relative(move)
        for cut in cuts_s:
            body.advance(body.t + cut)
        body.advance(body.t + 100.0)
        assert not body.moving
    return body.true_pose()


def test_a_whole_number_of_segments_is_driven_alike_however_the_steps_fall() -> None:
    """Summing a leg step by step once landed a hair past 762 segments: one slicing
    drove 762 + a 1e-16 m segment, another 761 + a 0.999.. mm one, and the extra
    draw shifted every later segment's noise (about 1 % of slicings did this). And
    a turn summed step by step ends 1e-16 rad apart, which the translation noise's
    factorisation once amplified to 1e-10 m."""
    reference = _two_legs_of_762_segments(0.0, ())
    slicing = np.random.default_rng(0)
    for _ in range(300):
        start = float(slicing.uniform(0.0, 10.0))
        cuts = tuple(float(c) for c in slicing.uniform(0.0, 1.5, size=slicing.integers(1, 4)))
        end = _two_legs_of_762_segments(start, cuts)
        assert np.allclose(end, reference, rtol=0.0, atol=1e-12), (start, cuts, end, reference)
