"""The discrete odometry error model as simulated, checked against its own definition.

Nothing here uses the closed forms: expected values are computed in the test
from eqs. (1)-(5) and (26)-(28) by direct summation over the segments, or
analytically. Statistical checks use fixed seeds and 4 Monte Carlo standard
errors.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import numpy.typing as npt
import pytest

from odohil.errors import ParameterError
from odohil.science.parameters import ErrorParameters
from odohil.science.paths import EncoderPath, Leg, Turn, forth_and_back, square
from odohil.science.simulator import (
    _add_translation_noise,
    _heading_sums,
    discrete_means,
    drive_straight,
    make_rng,
    segments_per_leg,
    simulate,
)

FloatArray = npt.NDArray[np.float64]
Z = 4.0
"""Tolerance in Monte Carlo standard errors."""

LOUD = ErrorParameters.from_paper_units(20.0, -0.05, 200.0, 1e-3)
"""Exaggerated errors: headings wander by tens of degrees over a few metres."""


def _segments(path: EncoderPath, segment_m: float) -> dict[str, FloatArray]:
    """Every segment of the path: sign, length, mean real heading, distance driven so far."""
    legs = path.legs
    sign, length, heading, signed_end, arc_end = [], [], [], [], []
    for j in range(len(legs.length_m)):
        count = segments_per_leg(float(legs.length_m[j]), segment_m)
        delta = float(legs.length_m[j]) / count
        i = np.arange(1, count + 1)
        sign.append(np.full(count, legs.sign[j]))
        length.append(np.full(count, delta))
        heading.append(np.full(count, legs.heading_rad[j]))
        signed_end.append(legs.start_signed_m[j] + legs.sign[j] * delta * i)
        arc_end.append(legs.start_arc_m[j] + delta * i)
    return {
        "sign": np.concatenate(sign),
        "delta": np.concatenate(length),
        "encoder_heading": np.concatenate(heading),
        "signed_end": np.concatenate(signed_end),
        "arc_end": np.concatenate(arc_end),
    }


def _mean_steps(
    path: EncoderPath, params: ErrorParameters, segment_m: float
) -> npt.NDArray[np.complex128]:
    """<rho_i e^{i theta_i}> for every segment, eq. (28) with the K_theta per metre reading."""
    seg = _segments(path, segment_m)
    mean_heading = seg["encoder_heading"] + params.e_r * seg["signed_end"]
    decay = np.exp(-0.5 * params.k_theta * seg["arc_end"])
    steps: npt.NDArray[np.complex128] = (
        seg["sign"] * (1.0 + params.e_t) * seg["delta"] * decay * np.exp(1j * mean_heading)
    )
    return steps


def discrete_mean_position(path: EncoderPath, params: ErrorParameters, segment_m: float) -> complex:
    """Exact <x + i y> of the discrete model (eq. 28 summed directly)."""
    return complex(_mean_steps(path, params, segment_m).sum())


def discrete_mean_square_distance(
    path: EncoderPath, params: ErrorParameters, segment_m: float
) -> float:
    """Exact <x^2 + y^2> of the discrete model, by summing over pairs of segments."""
    seg = _segments(path, segment_m)
    mean_rho = seg["sign"] * (1.0 + params.e_t) * seg["delta"]
    mean_heading = seg["encoder_heading"] + params.e_r * seg["signed_end"]
    arc = seg["arc_end"]
    diagonal = float(np.sum(mean_rho**2 + params.k_rho * seg["delta"]))
    # pair k < l: <e^{i(theta_l - theta_k)}> = e^{i(mean difference)} e^{-K_theta (arc_l - arc_k)/2}
    gap = arc[None, :] - arc[:, None]
    phase = np.exp(1j * (mean_heading[None, :] - mean_heading[:, None]))
    pair = np.outer(mean_rho, mean_rho) * phase * np.exp(-0.5 * params.k_theta * np.abs(gap))
    off = float(np.triu(pair, k=1).real.sum())
    return diagonal + 2.0 * off


def assert_mean(sample: FloatArray, expected: float, label: str) -> None:
    se = float(sample.std(ddof=1)) / math.sqrt(sample.size)
    assert abs(float(sample.mean()) - expected) <= Z * se, (
        f"{label}: mean {sample.mean():.6g} vs {expected:.6g}, SE {se:.3g}"
    )


def assert_same_mean(a: FloatArray, b: FloatArray, label: str) -> None:
    se = math.sqrt(float(a.var(ddof=1)) / a.size + float(b.var(ddof=1)) / b.size)
    assert abs(float(a.mean() - b.mean())) <= Z * se, (
        f"{label}: {a.mean():.6g} vs {b.mean():.6g}, SE {se:.3g}"
    )


def assert_same_covariance(a: FloatArray, b: FloatArray, label: str) -> None:
    """Each covariance entry of two (n, d) samples agrees within 4 SE."""
    da = a - a.mean(axis=0)
    db = b - b.mean(axis=0)
    for i in range(a.shape[1]):
        for j in range(i, a.shape[1]):
            assert_same_mean(da[:, i] * da[:, j], db[:, i] * db[:, j], f"{label} cov[{i},{j}]")


PATHS = {
    "one leg": EncoderPath((Leg(2.0),)),
    "k=1 turn": forth_and_back(1, 1.5, "turn"),
    "k=1.5 reverse": forth_and_back(1.5, 1.0, "reverse"),
    "square": square(1.0),
    "mixed": EncoderPath((Leg(0.7), Turn(0.4), Leg(-1.1), Turn(-2.0), Leg(0.93))),
}


@pytest.mark.parametrize("name", sorted(PATHS))
def test_heading_change_is_normal_with_the_model_mean_and_variance(name: str) -> None:
    path = PATHS[name]
    n = 100_000
    delta = simulate(path, LOUD, n, seed=11, segment_m=0.013).pose_change[:, 2]
    mean = LOUD.e_r * path.signed_distance_m + path.net_turn_rad - path.winding_rad
    var = LOUD.k_theta * path.distance_m
    assert_mean(delta, mean, "mean of Delta")
    # SE of a sample variance of a normal sample: var * sqrt(2 / (n - 1))
    assert abs(float(delta.var(ddof=1)) - var) <= Z * var * math.sqrt(2.0 / (n - 1))
    standard = (delta - mean) / math.sqrt(var)
    assert abs(float(np.mean(standard**3))) <= Z * math.sqrt(15.0 / n)
    assert abs(float(np.mean(standard**4)) - 3.0) <= Z * math.sqrt(96.0 / n)


@pytest.mark.parametrize(
    ("name", "segment_m"),
    [("one leg", 0.1), ("k=1 turn", 0.15), ("k=1.5 reverse", 0.125), ("mixed", 0.05)],
)
def test_mean_position_is_the_exact_discrete_sum(name: str, segment_m: float) -> None:
    path = PATHS[name]
    n = 200_000
    pose = simulate(path, LOUD, n, seed=12, segment_m=segment_m).pose_change
    expected = discrete_mean_position(path, LOUD, segment_m)
    assert_mean(pose[:, 0], expected.real, "<x>")
    assert_mean(pose[:, 1], expected.imag, "<y>")
    # the test can tell the discrete model from its N -> infinity limit
    finer = discrete_mean_position(path, LOUD, segment_m / 64)
    se = float(pose[:, :2].std(axis=0).max()) / math.sqrt(n)
    assert abs(expected - finer) > 10 * se


@pytest.mark.parametrize("name", ["k=1 turn", "k=1.5 reverse", "mixed"])
def test_mean_square_distance_is_the_exact_discrete_sum(name: str) -> None:
    path = PATHS[name]
    segment_m = 0.02
    pose = simulate(path, LOUD, 100_000, seed=13, segment_m=segment_m).pose_change
    distance2 = pose[:, 0] ** 2 + pose[:, 1] ** 2
    assert_mean(distance2, discrete_mean_square_distance(path, LOUD, segment_m), "<D^2>")


@pytest.mark.parametrize("name", sorted(PATHS))
def test_library_discrete_means_match_the_direct_pair_sums(name: str) -> None:
    path = PATHS[name]
    means = discrete_means(path, LOUD, 0.011)
    position = discrete_mean_position(path, LOUD, 0.011)
    assert means.x == pytest.approx(position.real, abs=1e-12)
    assert means.y == pytest.approx(position.imag, abs=1e-12)
    expected = discrete_mean_square_distance(path, LOUD, 0.011)
    assert means.square_distance == pytest.approx(expected, rel=1e-12)


def _straight_leg_limit(params: ErrorParameters, length_m: float) -> complex:
    """(1 + E_T) int_0^l e^{(i E_R - K_theta/2) s} ds: <x + i y> as N -> infinity."""
    a = 0.5 * params.k_theta - 1j * params.e_r
    return complex((1.0 + params.e_t) * (1.0 - np.exp(-a * length_m)) / a)


def test_noise_free_simulation_converges_linearly_in_the_segment_length() -> None:
    params = ErrorParameters.from_paper_units(40.0, -0.05, 0.0, 0.0)
    length = 3.0
    path = EncoderPath((Leg(length),))
    limit = _straight_leg_limit(params, length)
    # right-endpoint sum: error = (delta/2)(f(l) - f(0)) + O(delta^2), f(s) = (1+E_T) e^{i E_R s}
    slope = 0.5 * (1.0 + params.e_t) * (np.exp(1j * params.e_r * length) - 1.0)
    ratios = []
    for count in (30, 60, 120, 240):
        segment = length / count
        pose = simulate(path, params, 3, seed=1, segment_m=segment).pose_change
        end = complex(pose[0, 0], pose[0, 1])
        ratios.append(abs((end - limit) / segment - slope) / abs(slope))
    assert ratios[0] < 0.1
    for coarse, fine in itertools.pairwise(ratios):
        assert fine < 0.6 * coarse  # the O(delta^2) remainder halves with delta


def test_mean_converges_linearly_in_the_segment_length() -> None:
    length = 3.0
    path = EncoderPath((Leg(length),))
    limit = _straight_leg_limit(LOUD, length)
    a = 0.5 * LOUD.k_theta - 1j * LOUD.e_r
    slope = 0.5 * (1.0 + LOUD.e_t) * (np.exp(-a * length) - 1.0)
    errors = []
    for count in (30, 60, 120, 240):
        segment = length / count
        error = discrete_mean_position(path, LOUD, segment) - limit
        assert abs(error / segment - slope) < 0.1 * abs(slope)
        errors.append(abs(error))
    for coarse, fine in itertools.pairwise(errors):
        assert fine == pytest.approx(coarse / 2, rel=0.05)


def test_float32_path_matches_float64_arithmetic_without_noise() -> None:
    params = ErrorParameters.from_paper_units(25.0, 0.03, 0.0, 0.0)
    path = PATHS["mixed"]
    segment_m = 0.001
    pose = simulate(path, params, 2, seed=3, segment_m=segment_m).pose_change
    expected = discrete_mean_position(path, params, segment_m)
    assert abs(complex(pose[0, 0], pose[0, 1]) - expected) < 1e-6 * path.distance_m
    assert pose[0, 2] == pytest.approx(
        params.e_r * path.signed_distance_m + path.net_turn_rad - path.winding_rad, abs=1e-12
    )


@pytest.mark.parametrize(
    ("e_r", "k_theta"),
    [(20.0, 300.0), (90.0, 1.0)],  # heading noise large; heading sweeping, translation noise rules
)
def test_per_leg_translation_noise_matches_per_segment_noise(e_r: float, k_theta: float) -> None:
    params = ErrorParameters.from_paper_units(e_r, -0.05, k_theta, 0.05)
    path = forth_and_back(1, 1.0, "turn")
    n = 20_000
    fast = simulate(path, params, n, seed=21, segment_m=0.02)
    literal = simulate(path, params, n, seed=22, segment_m=0.02, trajectory=True)
    assert literal.trajectory is not None
    assert fast.trajectory is None
    np.testing.assert_array_equal(literal.trajectory[:, -1, :2], literal.pose_change[:, :2])
    for i, label in enumerate(("x", "y", "Delta")):
        assert_same_mean(fast.pose_change[:, i], literal.pose_change[:, i], f"<{label}>")
    assert_same_covariance(fast.pose_change, literal.pose_change, "(x, y, Delta)")


def test_fast_path_moments_match_literal_float64_path() -> None:
    """Float32 heading sums do not bias moments (checked against float64 throughout)."""
    path = PATHS["mixed"]
    n = 40_000
    fast = simulate(path, LOUD, n, seed=31, segment_m=0.01).pose_change
    literal = simulate(path, LOUD, n, seed=32, segment_m=0.01, trajectory=True).pose_change
    assert_same_mean(fast[:, 0], literal[:, 0], "<x>")
    assert_same_mean(fast[:, 1], literal[:, 1], "<y>")
    assert_same_mean(
        fast[:, 0] ** 2 + fast[:, 1] ** 2, literal[:, 0] ** 2 + literal[:, 1] ** 2, "<D^2>"
    )
    assert_same_covariance(fast, literal, "(x, y, Delta)")


def _drive(pieces: list[int], n: int, seed: int) -> FloatArray:
    rng = make_rng(seed)
    x, y, theta = np.zeros(n), np.zeros(n), np.full(n, 0.3)
    for count in pieces:
        drive_straight(x, y, theta, -0.004, count, LOUD, rng)
    return np.column_stack([x, y, theta])


def test_driving_in_pieces_is_distributed_like_one_call() -> None:
    n = 20_000
    whole = _drive([300], n, seed=41)
    pieces = [1] * 40 + [7] * 20 + [3] * 30 + [30]
    assert sum(pieces) == 300
    ticks = _drive(pieces, n, seed=42)
    for i, label in enumerate(("x", "y", "theta")):
        assert_same_mean(whole[:, i], ticks[:, i], f"<{label}>")
    assert_same_covariance(whole, ticks, "(x, y, theta)")


def test_tick_sized_calls_are_distributed_like_one_call() -> None:
    """One segment per call, as the fake robot drives, for a few hundred trials at a time."""
    groups, size = 50, 200
    rng = make_rng(43)
    poses = []
    for _ in range(groups):
        x, y, theta = np.zeros(size), np.zeros(size), np.full(size, 0.3)
        for _ in range(300):
            drive_straight(x, y, theta, -0.004, 1, LOUD, rng)
        poses.append(np.column_stack([x, y, theta]))
    ticks = np.vstack(poses)
    whole = _drive([300], groups * size, seed=44)
    for i, label in enumerate(("x", "y", "theta")):
        assert_same_mean(whole[:, i], ticks[:, i], f"<{label}>")
    assert_same_covariance(whole, ticks, "(x, y, theta)")


def test_seeds_reproduce_exactly() -> None:
    path = PATHS["k=1 turn"]
    first = simulate(path, LOUD, 3000, seed=5, segment_m=0.01).pose_change
    again = simulate(path, LOUD, 3000, seed=5, segment_m=0.01).pose_change
    other = simulate(path, LOUD, 3000, seed=6, segment_m=0.01).pose_change
    np.testing.assert_array_equal(first, again)
    assert not np.any(first == other)
    via_generator = simulate(path, LOUD, 3000, seed=np.random.default_rng(5), segment_m=0.01)
    np.testing.assert_array_equal(first, via_generator.pose_change)


@pytest.mark.parametrize(
    "params",
    [LOUD, ErrorParameters(0.01, 0.002, 1e-3, 1e-5), ErrorParameters(0.02, 0.01, 2e-4, 0.0)],
    ids=["loud", "nomad-like", "no-translation-noise"],
)
def test_a_single_trial_is_the_array_paths_arithmetic_bit_for_bit(
    params: ErrorParameters,
) -> None:
    """drive_straight keeps a single trial's float64 sums in Python floats (the
    fakes' calls); the arrays' path, run by hand on a one-element array with
    the same seed, must give the same bits and leave the generator in the same
    state."""
    for count in (1, 2, 3, 6, 128, 129, 300):
        for signed_segment_m in (0.001, -0.004):
            one = make_rng(count)
            x, y, theta = np.array([0.1]), np.array([-0.2]), np.array([0.3])
            drive_straight(x, y, theta, signed_segment_m, count, params, one)
            arrays = make_rng(count)
            ax, ay, at = np.array([0.1]), np.array([-0.2]), np.array([0.3])
            delta = abs(signed_segment_m)
            rho_sd = math.sqrt(params.k_rho * delta)
            sums = _heading_sums(
                at,
                count,
                math.sqrt(params.k_theta * delta),
                params.e_r * signed_segment_m,
                arrays,
                rho_sd > 0.0,
            )
            ax += (1.0 + params.e_t) * signed_segment_m * sums.cos
            ay += (1.0 + params.e_t) * signed_segment_m * sums.sin
            if rho_sd > 0.0:
                _add_translation_noise(ax, ay, sums, count, rho_sd, arrays)
            assert (x.tobytes(), y.tobytes(), theta.tobytes()) == (
                ax.tobytes(),
                ay.tobytes(),
                at.tobytes(),
            ), (count, signed_segment_m)
            assert one.bit_generator.state == arrays.bit_generator.state


def test_progress_reports_every_trial_once_in_order() -> None:
    seen: list[int] = []
    simulate(PATHS["one leg"], LOUD, 10_000, seed=1, segment_m=0.1, progress=seen.append)
    assert seen == sorted(seen)
    assert seen[-1] == 10_000


@pytest.mark.parametrize("n_trials", [0, -3])
def test_bad_trial_count_raises(n_trials: int) -> None:
    with pytest.raises(ParameterError):
        simulate(PATHS["one leg"], LOUD, n_trials)


@pytest.mark.parametrize("segment_m", [0.0, -0.01, math.nan, math.inf])
def test_bad_segment_length_raises(segment_m: float) -> None:
    with pytest.raises(ParameterError):
        simulate(PATHS["one leg"], LOUD, 10, segment_m=segment_m)


@pytest.mark.parametrize(("segment_m", "count"), [(0.0, 3), (math.nan, 3), (0.01, -1)])
def test_drive_straight_rejects_bad_arguments(segment_m: float, count: int) -> None:
    x, y, theta = np.zeros(4), np.zeros(4), np.zeros(4)
    with pytest.raises(ParameterError):
        drive_straight(x, y, theta, segment_m, count, LOUD, make_rng(0))


def test_drive_straight_rejects_mismatched_pose_arrays() -> None:
    with pytest.raises(ParameterError):
        drive_straight(np.zeros(4), np.zeros(3), np.zeros(4), 0.01, 3, LOUD, make_rng(0))
