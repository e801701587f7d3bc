"""Closed forms of phi1..phi5, <x>, <y> for forth-and-back designs (eqs. 33-40).

Checked against the general path integrals (pose_moments, ~1e-10), against
their exact limits, and against the simulator within 4 Monte Carlo standard
errors; the paper's printed eq. (40) and its printed decay fail the same test.
"""

from __future__ import annotations

import cmath
import math

import numpy as np
import pytest

from odohil.science.closed_forms import (
    ObservableMeans,
    forth_and_back_means,
    geometric_sum,
    weighted_geometric_sum,
    z_parameter,
)
from odohil.science.moments import observable_means
from odohil.science.observables import observables
from odohil.science.parameters import NOMAD150, ErrorParameters
from odohil.science.paths import Design, EncoderPath
from odohil.science.simulator import segments_per_leg, simulate

EXAGGERATED = ErrorParameters.from_paper_units(20.0, -0.05, 200.0, 1e-3)
"""Every term matters: E_R 20 deg/m, 1+E_T 0.95, K_theta 200 deg^2/m, K_rho 1 mm."""

KEYS = ("phi1", "phi2", "phi3", "phi4", "phi5")


def printed_eq_40(design: Design, params: ErrorParameters) -> float:
    """<phi5> exactly as printed in the paper (integer k only)."""
    k, l_m, gain = design.k, design.l_m, 1.0 + params.e_t
    z = z_parameter(design, params)
    braces = (
        (cmath.exp(-z) - 1) ** 2 * (1 - cmath.exp(2 * k * z)) + 4 * k * (cmath.exp(-2 * z) - 1)
    ) / (z * z * (1 + cmath.exp(-z)) ** 2) + 2 * k / z
    return 2 * params.k_rho * k * l_m + 2 * gain**2 * l_m**2 * braces.real


def discrete_means(
    path: EncoderPath, params: ErrorParameters, segment_m: float
) -> tuple[complex, float]:
    """Exact E[x + iy] (eq. 28) and E[x^2 + y^2] of the simulator's discrete model."""
    legs = path.legs
    a_parts, s_parts = [], []
    for j in range(legs.length_m.size):
        n = segments_per_leg(float(legs.length_m[j]), segment_m)
        delta = legs.length_m[j] / n
        step = np.arange(1, n + 1) * delta
        theta = legs.heading_rad[j] + params.e_r * (legs.start_signed_m[j] + legs.sign[j] * step)
        a_parts.append((1 + params.e_t) * legs.sign[j] * delta * np.exp(1j * theta))
        s_parts.append(legs.start_arc_m[j] + step)
    a, s = np.concatenate(a_parts), np.concatenate(s_parts)
    k = params.k_theta
    mean = complex(np.sum(a * np.exp(-k * s / 2)))
    grow = a * np.exp(k * s / 2)
    before = np.cumsum(grow) - grow
    cross = np.sum(np.conj(a) * np.exp(-k * s / 2) * before).real
    square = float(np.sum(np.abs(a) ** 2) + 2 * cross + params.k_rho * path.distance_m)
    return mean, square


DESIGNS = [
    Design(k, l_m, v)
    for k, l_m in ((0.5, 1.0), (1, 6.0), (1.5, 1.0), (2, 0.5), (20, 0.5))
    for v in ("turn", "reverse")
]
BACKWARD = [Design(k, 1.0, v, backward=True) for k in (0.5, 1.5, 2) for v in ("turn", "reverse")]


@pytest.mark.parametrize("params", [NOMAD150, EXAGGERATED, ErrorParameters(0.3, 0.1, 0.0, 0.0)])
@pytest.mark.parametrize("design", DESIGNS + BACKWARD, ids=Design.label)
def test_closed_forms_equal_the_path_integrals(design: Design, params: ErrorParameters) -> None:
    closed = forth_and_back_means(design, params)
    general = observable_means(design.path(), params)
    rho = design.distance_m
    scale = {"phi1": 1.0, "phi2": 1.0, "phi3": rho, "phi4": rho, "x": rho, "y": rho, "phi5": rho**2}
    for key, value in closed.as_dict().items():
        assert abs(value - general.as_dict()[key]) < 1e-10 * scale[key], key
    assert closed.phi3 == closed.x
    assert closed.phi4 == closed.y


@pytest.mark.parametrize("k", [0.5, 1, 1.5, 20])
@pytest.mark.parametrize("variant", ["turn", "reverse"])
def test_zero_rotational_error_gives_exact_limits(k: float, variant: str) -> None:
    design = Design(k, 2.0, variant)  # type: ignore[arg-type]
    params = ErrorParameters(e_r=0.0, e_t=0.1, k_theta=0.0, k_rho=1e-3)
    means = forth_and_back_means(design, params)
    odd = design.n_legs % 2 == 1
    # no rotation error: the robot ends where the encoders say, scaled by 1 + E_T
    assert means.x == pytest.approx(2.2 if odd else 0.0, abs=1e-15)
    assert means.y == 0.0
    assert means.phi1 == 0.0
    assert means.phi2 == 0.0
    assert means.phi5 == pytest.approx((2.2**2 if odd else 0.0) + 1e-3 * design.distance_m)
    # and z -> 0 is continuous
    tiny = ErrorParameters(e_r=1e-9, e_t=0.1, k_theta=1e-12, k_rho=1e-3)
    near = forth_and_back_means(design, tiny)
    assert near.x == pytest.approx(means.x, abs=1e-8)
    assert near.phi5 == pytest.approx(means.phi5, rel=1e-8)


@pytest.mark.parametrize("variant", ["turn", "reverse"])
def test_half_turn_drift_is_a_removable_singularity(variant: str) -> None:
    # E_R l = pi makes the printed geometric sums 0/0
    design = Design(2, 1.0, variant)  # type: ignore[arg-type]
    params = ErrorParameters(math.pi, 0.0, 0.0, 0.0)
    at = forth_and_back_means(design, params).as_dict()
    near = forth_and_back_means(design, ErrorParameters(math.pi * (1 + 1e-10), 0.0, 0, 0))
    general = observable_means(design.path(), params).as_dict()
    for key in KEYS:
        assert math.isfinite(at[key])
        assert at[key] == pytest.approx(near.as_dict()[key], abs=1e-8)
        assert at[key] == pytest.approx(general[key], abs=1e-12)


def test_geometric_sums_match_term_by_term() -> None:
    for q in (0.3, -0.97, 1.0, 0.9999 + 0.01j, cmath.exp(-0.2 + 2.5j), -1.0):
        for m in (1, 2, 3, 7, 40):
            s = sum(q**j for j in range(m))
            w = sum((m - d) * q ** (d - 1) for d in range(1, m))
            assert geometric_sum(q, m) == pytest.approx(s, rel=1e-12, abs=1e-12)
            assert weighted_geometric_sum(q, m) == pytest.approx(w, rel=1e-12, abs=1e-12)


def test_corrected_eq_40_differs_from_the_printed_one_only_in_the_sign() -> None:
    # with e^{2kz} -> e^{-2kz} the printed expression equals the corrected one
    design, params = Design(3, 1.0), EXAGGERATED
    k, l_m, gain = design.k, design.l_m, 1.0 + params.e_t
    z = z_parameter(design, params)
    braces = (
        (cmath.exp(-z) - 1) ** 2 * (1 - cmath.exp(-2 * k * z)) + 4 * k * (cmath.exp(-2 * z) - 1)
    ) / (z * z * (1 + cmath.exp(-z)) ** 2) + 2 * k / z
    fixed = 2 * params.k_rho * k * l_m + 2 * gain**2 * l_m**2 * braces.real
    assert forth_and_back_means(design, params).phi5 == pytest.approx(fixed, rel=1e-12)
    assert printed_eq_40(design, params) != pytest.approx(fixed, rel=1e-2)


def _check_against_simulation(
    means: ObservableMeans, path: EncoderPath, params: ErrorParameters, n: int, segment_m: float
) -> dict[str, float]:
    """Assert bias < SE/5 and |closed form - sample| < 4 SE; return the z-scores."""
    data = simulate(path, params, n, seed=4242, segment_m=segment_m).pose_change
    obs = observables(data)
    delta, x, y = data[:, 2], data[:, 0], data[:, 1]
    se = {
        "phi1": delta.std(ddof=1) / math.sqrt(n),
        "phi2": ((delta - delta.mean()) ** 2).std(ddof=1) / math.sqrt(n),
        "phi3": x.std(ddof=1) / math.sqrt(n),
        "phi4": y.std(ddof=1) / math.sqrt(n),
        "phi5": (x * x + y * y).std(ddof=1) / math.sqrt(n),
    }
    mean_z, square = discrete_means(path, params, segment_m)
    bias = {"phi3": mean_z.real - means.x, "phi4": mean_z.imag - means.y}
    bias["phi5"] = square - means.phi5
    for key, value in bias.items():
        assert abs(value) < se[key] / 5, (key, value, se[key])
    scores = {key: (obs.as_dict()[key] - means.as_dict()[key]) / se[key] for key in KEYS}
    for key, score in scores.items():
        assert abs(score) < 4, (key, scores)
    return scores


SIMULATED = [
    (Design(1, 6.0, "turn"), NOMAD150, 4000, 0.05),
    (Design(20, 0.5, "turn"), NOMAD150, 4000, 0.01),
    (Design(1, 6.0, "reverse"), NOMAD150, 4000, 0.002),
    # reversing 40 times: the discrete model's y bias adds up leg by leg while
    # the spread cancels, so fewer trials and shorter segments
    (Design(20, 0.5, "reverse"), NOMAD150, 400, 0.0005),
    *[
        (d, EXAGGERATED, 4000, 0.001)
        for d in DESIGNS
        if d.l_m < 6 and not (d.variant == "reverse" and d.n_legs > 3)
    ],
    (Design(2, 0.5, "reverse"), EXAGGERATED, 4000, 0.0005),
    (Design(20, 0.5, "reverse"), EXAGGERATED, 400, 0.0005),
    # one-way trials driven backwards come back: the mirror image, predicted exactly
    *[(d, EXAGGERATED, 4000, 0.001) for d in BACKWARD if d.n_legs < 4],
]


@pytest.mark.parametrize(
    ("design", "params", "n", "segment_m"),
    SIMULATED,
    ids=[f"{d.label()} {'nomad' if p is NOMAD150 else 'big'}" for d, p, _, _ in SIMULATED],
)
def test_closed_forms_agree_with_the_simulator(
    design: Design, params: ErrorParameters, n: int, segment_m: float
) -> None:
    means = forth_and_back_means(design, params)
    _check_against_simulation(means, design.path(), params, n, segment_m)


@pytest.mark.parametrize(
    ("design", "params"), [(Design(1, 6.0), NOMAD150), (Design(1, 2.0), EXAGGERATED)]
)
def test_printed_eq_40_misses_the_simulator(design: Design, params: ErrorParameters) -> None:
    n = 20000
    data = simulate(design.path(), params, n, seed=99, segment_m=0.01).pose_change
    distance2 = data[:, 0] ** 2 + data[:, 1] ** 2
    se = distance2.std(ddof=1) / math.sqrt(n)
    corrected = forth_and_back_means(design, params).phi5
    _, discrete = discrete_means(design.path(), params, 0.01)
    assert abs(discrete - corrected) < se / 5
    assert abs(distance2.mean() - corrected) < 4 * se
    assert abs(distance2.mean() - printed_eq_40(design, params)) > 10 * se


def test_printed_decay_misses_the_simulator() -> None:
    # decay e^{-sigma_theta^2 s/2} with sigma_theta^2 = K_theta rho, read literally
    design, params = Design(1, 2.0), EXAGGERATED
    literal = ErrorParameters(
        params.e_r, params.e_t, params.k_theta * design.distance_m, params.k_rho
    )
    n = 4000
    data = simulate(design.path(), params, n, seed=5, segment_m=0.002).pose_change
    distance2 = data[:, 0] ** 2 + data[:, 1] ** 2
    sample = np.array([data[:, 0].mean(), data[:, 1].mean(), distance2.mean()])
    se = np.array([data[:, 0].std(), data[:, 1].std(), distance2.std()]) / math.sqrt(n)
    wrong = observable_means(design.path(), literal)
    right = forth_and_back_means(design, params)
    assert np.max(np.abs(sample - [wrong.x, wrong.y, wrong.phi5]) / se) > 10
    assert np.max(np.abs(sample - [right.x, right.y, right.phi5]) / se) < 4


@pytest.mark.parametrize("variant", ["turn", "reverse"])
def test_a_backward_one_way_trial_ends_where_the_forward_one_started(variant: str) -> None:
    ahead = Design(1.5, 2.0, variant)  # type: ignore[arg-type]
    back = ahead.mirrored
    assert back.backward
    assert back.path().distance_m == ahead.path().distance_m
    x_out, y_out, _ = ahead.path().encoder_end_pose()
    x_back, y_back, _ = back.path().encoder_end_pose()
    assert (x_out, y_out) == pytest.approx((2.0, 0.0), abs=1e-12)
    assert (x_back, y_back) == pytest.approx((-2.0, 0.0), abs=1e-12)
    # the model's mean pose change is the forward one mirrored (x, theta negated)
    forward_means, backward_means = (observable_means(d.path(), EXAGGERATED) for d in (ahead, back))
    assert backward_means.x == pytest.approx(-forward_means.x, rel=1e-12)
    assert backward_means.y == pytest.approx(forward_means.y, rel=1e-12)
    assert backward_means.phi1 == pytest.approx(-forward_means.phi1, rel=1e-12)
