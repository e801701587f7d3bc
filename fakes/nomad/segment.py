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

:func:`drive_segments` drives many equal segments at once with the same draws
and the same arithmetic (fakes/nomad/draws.py reads numpy's words in bulk;
the sums run in order through ``np.cumsum``, the logarithms and trigonometry
through :mod:`math`, whose results numpy's vector functions need not match to
the last bit): the same poses to the last bit.
"""

from __future__ import annotations

import bisect
import math

import numpy as np

from fakes.nomad.draws import (
    UNIFORM_SCALE,
    ZigguratTables,
    one_word_normals,
    uniforms,
    ziggurat_tables,
)
from odohil.science.parameters import ErrorParameters

FEW = 4
"""Fewer segments than this are driven by :func:`drive_segment` itself..."""
MIN_BATCH = 48
"""...fewer than this one by one with their uniforms made of one word each
(no numpy call for them), and from here in bulk (whose fixed price, some
forty numpy calls, is worth it from about here)."""
LOOK_AHEAD = 64
"""How many words past a segment's first four the word after its normals is
looked for (each word more is a rejection in numpy's ziggurat, of chance
below 1 %; beyond this the segments are driven one by one)."""


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


def drive_segments(
    pose: tuple[float, float, float],
    signed_segment_m: float,
    n: int,
    params: ErrorParameters,
    rng: np.random.Generator,
) -> tuple[float, float, float]:
    """The true pose after ``n`` segments of signed encoder length
    ``signed_segment_m`` from ``pose``: exactly ``n`` calls of
    :func:`drive_segment` (the same draws, the same pose to the last bit, the
    generator left at the same place in its stream), in bulk where it can."""
    bits = rng.bit_generator
    if n < FEW or type(bits) is not np.random.PCG64 or bits.state["has_uint32"]:
        for _ in range(n):
            pose = drive_segment(pose, signed_segment_m, params, rng)
        return pose
    tables = ziggurat_tables() if n >= MIN_BATCH else None
    if tables is None:
        return _one_by_one(pose, signed_segment_m, n, params, rng, bits)
    if math.sqrt(params.k_rho * abs(signed_segment_m)) > 0.0:
        found = _noisy_draws(n, rng, bits, tables)
        if found is None:  # the words drawn in bulk ran out (the generator is back)
            return _one_by_one(pose, signed_segment_m, n, params, rng, bits)
        uniform_words, z0 = found
        return _segments(pose, signed_segment_m, params, uniform_words, z0)
    return _segments(pose, signed_segment_m, params, bits.random_raw(n), None)


def _one_by_one(
    pose: tuple[float, float, float],
    signed_segment_m: float,
    n: int,
    params: ErrorParameters,
    rng: np.random.Generator,
    bits: np.random.PCG64,
) -> tuple[float, float, float]:
    """:func:`drive_segment` ``n`` times, each segment's uniforms made of one
    word of ``bits`` (no 32-bit half left over in it: see fakes/nomad/draws.py)."""
    x, y, heading = pose
    delta = abs(signed_segment_m)
    heading_sd = math.sqrt(params.k_theta * delta)
    rho_sd = math.sqrt(params.k_rho * delta)
    turn = params.e_r * signed_segment_m
    step = (1.0 + params.e_t) * signed_segment_m
    two_pi = 2.0 * math.pi
    normals = rng.standard_normal
    for _ in range(n):
        word = bits.random_raw()
        u = ((word & 0xFFFF_FFFF) >> 8) * UNIFORM_SCALE
        v = (word >> 40) * UNIFORM_SCALE
        normal = math.sqrt(-2.0 * math.log(1.0 - u)) * math.cos(two_pi * v)
        heading = heading + heading_sd * normal + turn
        cos_h, sin_h = math.cos(heading), math.sin(heading)
        x += step * cos_h
        y += step * sin_h
        if rho_sd > 0.0:
            z0, _ = normals(2).tolist()
            along = rho_sd * z0 * math.copysign(1.0, cos_h)
            x += along * cos_h
            y += along * sin_h
    return (x, y, heading)


def _noisy_draws(
    n: int, rng: np.random.Generator, bits: np.random.PCG64, tables: ZigguratTables
) -> tuple[np.ndarray, np.ndarray] | None:
    """The words of ``n`` segments' uniforms and their first normals, the
    generator left after the segments' last draw; None (the generator back where
    it was) in the rare case that the words drawn in bulk run out or a
    segment's normals read more than :data:`LOOK_AHEAD` words.

    A segment reads three words when both its normals take one (numpy's
    ziggurat, about 99 % of normals): those normals are computed from the words
    here. At a segment whose normals read more, numpy draws them itself, and the
    word that follows them tells where the next segment begins."""
    start = bits.state
    words = bits.random_raw(3 * n + n // 8 + 16)
    normals, one_word = one_word_normals(words, tables)
    slow_words = np.flatnonzero(~one_word).tolist()
    total = len(words)
    steps = np.full(n, 3)  # the words each segment reads
    numpy_z0: dict[int, float] = {}  # segment -> its first normal, as numpy drew it
    pos = done = k = 0
    while True:
        # the next segment from ``pos`` on with a normal that reads more than a
        # word: the first slow word that is not a segment's uniforms
        k = bisect.bisect_left(slow_words, pos + 1, k)
        while k < len(slow_words) and (slow_words[k] - pos) % 3 == 0:
            k += 1
        quick = (slow_words[k] - pos - 1) // 3 if k < len(slow_words) else (total - pos) // 3
        good = min(n - done, quick)
        pos += 3 * good
        done += good
        if done == n:
            break
        if k == len(slow_words):  # the words ran out
            bits.state = start
            return None
        bits.state = start  # numpy draws this segment's two normals
        bits.advance(pos + 1)
        first, _ = rng.standard_normal(2).tolist()
        following = np.flatnonzero(words[pos + 4 : pos + 4 + LOOK_AHEAD] == bits.random_raw())
        if following.size == 0:
            bits.state = start
            return None
        numpy_z0[done] = first
        step = 4 + int(following[0])
        steps[done] = step
        pos += step
        done += 1
    bits.state = start
    bits.advance(pos)
    at = np.cumsum(steps) - steps
    z0 = normals[at + 1]
    for segment, value in numpy_z0.items():
        z0[segment] = value
    return words[at], z0


def _segments(
    pose: tuple[float, float, float],
    signed_segment_m: float,
    params: ErrorParameters,
    words: np.ndarray,
    z0: np.ndarray | None,
) -> tuple[float, float, float]:
    """:func:`drive_segment` over ``len(words)`` segments: each one's uniform
    word and (with translation noise) first normal given."""
    x, y, start = pose
    k = len(words)
    delta = abs(signed_segment_m)
    heading_sd = math.sqrt(params.k_theta * delta)
    rho_sd = math.sqrt(params.k_rho * delta)
    u, v = uniforms(words)
    radius = np.sqrt(-2.0 * np.fromiter(map(math.log, (1.0 - u).tolist()), np.float64, k))
    angle = np.fromiter(map(math.cos, (2.0 * math.pi * v).tolist()), np.float64, k)
    # heading = previous + heading_sd * normal + e_r * segment, added in that order
    terms = np.empty(2 * k + 1)
    terms[0] = start
    terms[1::2] = heading_sd * (radius * angle)
    terms[2::2] = params.e_r * signed_segment_m
    heading = np.cumsum(terms)[2::2]
    listed = heading.tolist()
    cos_h = np.fromiter(map(math.cos, listed), np.float64, k)
    sin_h = np.fromiter(map(math.sin, listed), np.float64, k)
    step = (1.0 + params.e_t) * signed_segment_m
    if z0 is None:
        x = _running_sum(x, step * cos_h)
        y = _running_sum(y, step * sin_h)
    else:
        along = rho_sd * z0 * np.copysign(1.0, cos_h)
        x = _running_sum(x, step * cos_h, along * cos_h)
        y = _running_sum(y, step * sin_h, along * sin_h)
    return (x, y, listed[-1])


def _running_sum(first: float, *terms: np.ndarray) -> float:
    """``first`` plus the terms one by one in order (segment by segment, each
    segment's terms in the order given), as a Python loop would add them."""
    every = np.empty(1 + len(terms) * len(terms[0]))
    every[0] = first
    for i, t in enumerate(terms):
        every[1 + i :: len(terms)] = t
    return float(np.cumsum(every)[-1])
