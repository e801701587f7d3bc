"""One segment of Martinelli's discrete model for the fake's single true pose.

The fake robot drives its one trial a segment at a time (each segment by its
own call, so that its random numbers do not depend on how the wall clock slices
a motion; see fakes/nomad/body.py). Through
:func:`odohil.science.simulator.drive_straight` each call would cost the batch
path's fixed price (some fifty numpy calls, about 100 µs), so the fake draws
here exactly the same random numbers in the same order (two float32 uniforms
for Box-Muller, then two normals for the translation noise) and does the same
arithmetic in Python floats: the true poses equal the simulator's to float32
rounding (tests/fake/test_segment.py checks it draw for draw).

One segment's translation noise lies along its heading. The simulator's general
factor of the noise covariance would take the square root of the rounding left
in ``1 - cos^2 - sin^2`` (~1e-8), which turns headings 1e-16 rad apart into
poses ~1e-11 m apart; the fake must give the same true pose however a motion
is sliced, so it uses the exact one-segment factor.
"""

from __future__ import annotations

import math

import numpy as np

from odohil.science.parameters import ErrorParameters


def drive_segment(
    pose: tuple[float, float, float],
    signed_segment_m: float,
    params: ErrorParameters,
    rng: np.random.Generator,
) -> tuple[float, float, float]:
    """The true pose (x m, y m, theta rad) after one segment of signed encoder
    length ``signed_segment_m`` from ``pose``."""
    x, y, start = pose
    delta = abs(signed_segment_m)
    heading_sd = math.sqrt(params.k_theta * delta)
    rho_sd = math.sqrt(params.k_rho * delta)
    u, v = rng.random(2, dtype=np.float32).tolist()  # the same two draws as two calls
    normal = math.sqrt(-2.0 * math.log(1.0 - u)) * math.cos(2.0 * math.pi * v)
    heading = start + heading_sd * normal + params.e_r * signed_segment_m
    cos_h, sin_h = math.cos(heading), math.sin(heading)
    step = (1.0 + params.e_t) * signed_segment_m
    x += step * cos_h
    y += step * sin_h
    if rho_sd > 0.0:
        z0, _ = rng.standard_normal(2).tolist()  # the second keeps the simulator's stream
        along = rho_sd * z0 * math.copysign(1.0, cos_h)
        x += along * cos_h
        y += along * sin_h
    return (x, y, heading)
