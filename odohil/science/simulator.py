"""Monte Carlo simulation of Martinelli's discrete odometry error model.

Each leg of an encoder path is cut into N segments of equal encoder length
delta-rho-bar. For segment i (eqs. 1-5):

    real heading   theta_i = theta_{i-1} + E_R delta-rho-bar + d-theta_i,
                   d-theta_i ~ N(0, K_theta |delta-rho-bar|)
    real distance  rho_i = (1 + E_T) delta-rho-bar + d-rho_i,
                   d-rho_i ~ N(0, K_rho |delta-rho-bar|)
    real position  p_i = p_{i-1} + rho_i (cos theta_i, sin theta_i)

so the translation of segment i uses the heading after its own rotation, as
in eqs. (26)-(28). In-place turns add their encoder angle exactly. As the
segments get shorter the result converges to the N -> infinity limit that the
closed forms describe; the discretisation error is O(delta-rho-bar).

Exact shortcut: given the headings, the sum of the translation noise terms of
a leg is a zero-mean Gaussian with covariance
K_rho delta [sum cos^2, sum cos sin; sum cos sin, sum sin^2], so it is drawn
once per leg rather than once per segment. This is exact in distribution.

Numerics of the fast path (``trajectory=False``): the heading increments are
float32 normals (Box-Muller), summed in blocks of at most ``_SEGMENT_BLOCK``
segments; within a block the heading relative to the block start is small and
exact enough in float32, its cos and sin use numpy's float32 SIMD trig, and the
block sums are accumulated and rotated by the block start heading in float64.
The heading carried from block to block, the end pose and all sums over a leg
are float64. ``tests/science/test_simulator.py`` checks that this does not bias
the moments against the literal float64 path (``trajectory=True``).
"""

from __future__ import annotations

import functools
import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from odohil.errors import ParameterError
from odohil.science.parameters import ErrorParameters
from odohil.science.paths import EncoderPath, FloatArray

DEFAULT_SEGMENT_M = 0.001
"""Default encoder length of one segment, metres."""

_TRIAL_BLOCK = 1024
"""Trials per block: the columns of the float32 work arrays."""
_SEGMENT_BLOCK = 128
"""Segments per block at most: the rows of the float32 work arrays."""
_ROW_LOOP_MIN_WIDTH = 256
_LITERAL_CHUNK_ELEMENTS = 1 << 18

SeedLike = int | np.random.Generator | None


def make_rng(seed: SeedLike) -> np.random.Generator:
    """A numpy Generator from a seed, an existing Generator, or None (fresh entropy)."""
    if isinstance(seed, np.random.Generator):
        return seed
    return np.random.default_rng(seed)


@dataclass(frozen=True)
class SimulationResult:
    """Simulated trials of one path.

    Attributes:
        pose_change: shape (n_trials, 3): real x (m), y (m) of the end point in
            the start frame and real heading change (rad) minus the path's
            winding (see :attr:`EncoderPath.winding_rad`), not wrapped.
        trajectory: with ``trajectory=True``, shape (n_trials, n_points, 3):
            the real pose (x m, y m, theta rad) at the start and after every
            segment (in-place turns add no point; theta is unwrapped and keeps
            the turns made before the segment); otherwise None.
        segment_m: the encoder length of the segments of each leg, per leg.
    """

    pose_change: FloatArray
    trajectory: FloatArray | None
    segment_m: FloatArray

    @property
    def n_trials(self) -> int:
        """Number of simulated trials."""
        return int(self.pose_change.shape[0])


def segments_per_leg(length_m: float, segment_m: float) -> int:
    """How many equal segments a leg of ``length_m`` is cut into (at most ``segment_m`` each)."""
    return max(1, math.ceil(length_m / segment_m - 1e-9))


def drive_straight(
    x: FloatArray,
    y: FloatArray,
    theta: FloatArray,
    signed_segment_m: float,
    n_segments: int,
    params: ErrorParameters,
    rng: np.random.Generator,
    trajectory: bool = False,
) -> FloatArray | None:
    """Drive ``n_segments`` segments of signed encoder length ``signed_segment_m``.

    Updates the real poses ``x``, ``y`` (m) and ``theta`` (rad) of every trial
    in place (float64 arrays of one shape (n,)). This is the one
    implementation of the discrete model (the fake robot's one-segment steps,
    fakes/nomad/segment.py, are tested draw for draw against it). With
    ``trajectory=True`` it draws the translation noise segment by segment and
    returns the poses after each segment, shape (n, n_segments, 3); otherwise
    it draws the translation noise of the whole call at once (exact, see the
    module docstring).
    """
    if not math.isfinite(signed_segment_m) or signed_segment_m == 0.0:
        raise ParameterError(f"a segment needs a finite non-zero length, got {signed_segment_m!r}")
    if n_segments < 0:
        raise ParameterError(f"n_segments cannot be negative, got {n_segments}")
    if not (x.shape == y.shape == theta.shape) or x.ndim != 1:
        raise ParameterError(
            f"x, y, theta must be 1-d arrays of one shape, got {x.shape}, {y.shape}, {theta.shape}"
        )
    if n_segments == 0:
        return np.empty((x.shape[0], 0, 3)) if trajectory else None
    if trajectory:
        return _drive_literal(x, y, theta, signed_segment_m, n_segments, params, rng)
    _drive_blocks(x, y, theta, signed_segment_m, n_segments, params, rng)
    return None


def _drive_blocks(
    x: FloatArray,
    y: FloatArray,
    theta: FloatArray,
    signed_segment_m: float,
    n_segments: int,
    params: ErrorParameters,
    rng: np.random.Generator,
) -> None:
    """The fast path of :func:`drive_straight`: blocks of float32 work arrays."""
    delta = abs(signed_segment_m)
    heading_sd = math.sqrt(params.k_theta * delta)
    rho_sd = math.sqrt(params.k_rho * delta)
    drift = params.e_r * signed_segment_m
    step = (1.0 + params.e_t) * signed_segment_m
    n = x.shape[0]
    if n == 1:
        _drive_one(x, y, theta, n_segments, heading_sd, rho_sd, drift, step, rng)
        return
    for lo in range(0, n, _TRIAL_BLOCK):
        hi = min(n, lo + _TRIAL_BLOCK)
        sums = _heading_sums(theta[lo:hi], n_segments, heading_sd, drift, rng, rho_sd > 0.0)
        x[lo:hi] += step * sums.cos
        y[lo:hi] += step * sums.sin
        if rho_sd > 0.0:
            _add_translation_noise(x[lo:hi], y[lo:hi], sums, n_segments, rho_sd, rng)


@dataclass(frozen=True)
class _HeadingSums:
    """Per-trial sums over the segments of one call, float64, shape (m,).

    ``cos``/``sin``: sum of cos/sin theta_i; ``cos2``/``sin2``: sum of
    cos/sin 2 theta_i (zeros unless asked for).
    """

    cos: FloatArray
    sin: FloatArray
    cos2: FloatArray
    sin2: FloatArray


@dataclass(frozen=True)
class _BlockSums:
    """Per-trial sums over the segments of one block, relative to the block's
    start heading (psi: the heading change since then), float64, shape (m,).

    ``walk_end``: the block's sum of standard normal heading increments;
    ``q``: sum sin^2(psi/2); ``h``: sum sin(psi)/2; ``hq``, ``h2``: sum h q
    and sum h^2 (None unless asked for).
    """

    walk_end: FloatArray
    q: FloatArray
    h: FloatArray
    hq: FloatArray | None
    h2: FloatArray | None


class _Workspace:
    """Preallocated float32 work arrays: ``rows`` segments by ``m`` trials."""

    def __init__(self, rows: int, m: int) -> None:
        half = (rows + 1) // 2
        self.z = np.empty((2 * half, m), dtype=np.float32)
        self.a = np.empty((rows, m), dtype=np.float32)
        self.uv = np.empty((2 * half, m), dtype=np.float32)

    def normals(self, rng: np.random.Generator, rows: int) -> npt.NDArray[np.float32]:
        """``rows`` x m standard normals (float32), by the Box-Muller transform.

        numpy's ziggurat costs about 9 ns per float32 normal here; Box-Muller
        on float32 uniforms with numpy's SIMD log/sqrt/sin/cos about 2.6 ns.
        The uniforms are multiples of 2^-24, so |z| <= sqrt(48 ln 2) = 5.77:
        the tails beyond are missing (probability 2e-9 per draw, variance
        low by a relative 3e-7, far below any Monte Carlo error here).
        The uniforms u (the first half rows) and v (the second) come from one
        call: the same numbers, in the same order, as two calls would draw.
        """
        half = (rows + 1) // 2
        uv, z = self.uv[: 2 * half], self.z[: 2 * half]
        rng.random(dtype=np.float32, out=uv)
        u, v = uv[:half], uv[half:]
        np.subtract(np.float32(1.0), u, out=u)  # in (0, 1]: log is finite
        np.log(u, out=u)
        np.multiply(u, np.float32(-2.0), out=u)
        np.sqrt(u, out=u)
        np.multiply(v, np.float32(2.0 * math.pi), out=v)
        np.cos(v, out=z[:half])
        np.sin(v, out=z[half:])
        pairs = z.reshape(2, half, z.shape[1])
        np.multiply(pairs, u, out=pairs)
        return z[:rows]


def _cumsum_rows(z: npt.NDArray[np.float32]) -> None:
    """Cumulative sum down the rows of ``z``, in place.

    A loop of whole-row SIMD adds; numpy's own cumsum is a scalar loop
    (about 3 ns per element along a row, 10 ns down a column).
    """
    if z.shape[0] == 1:
        return
    if z.shape[1] < _ROW_LOOP_MIN_WIDTH:
        np.add.accumulate(z, axis=0, out=z)  # np.cumsum's own loop, without its wrapper
        return
    rows = list(z)
    for previous, row in itertools.pairwise(rows):
        np.add(previous, row, out=row)


@functools.lru_cache(maxsize=256)
def _half_drift(drift: float, rows: int) -> npt.NDArray[np.float32]:
    """Half the systematic heading change after each of a block's segments,
    float32 (rad), shape (rows, 1); read-only (shared between calls)."""
    values = (0.5 * drift * np.arange(1, rows + 1, dtype=np.float64)).astype(np.float32)
    values.flags.writeable = False
    return values[:, None]


def _block_sums(
    work: _Workspace,
    rng: np.random.Generator,
    count: int,
    half_sd: np.float32,
    half_drift: npt.NDArray[np.float32],
    second: bool,
) -> _BlockSums:
    """Draw the heading increments of one block of ``count`` segments and sum
    what the heading sums need (see :func:`_heading_sums`), in float32 work
    arrays with float64 sums."""
    z = work.normals(rng, count)
    _cumsum_rows(z)
    walk_end = z[-1].astype(np.float64)
    # z becomes psi/2, then h = sin(psi)/2 = sin(psi/2) cos(psi/2);
    # a becomes q = sin^2(psi/2), so cos psi = 1 - 2q and sin psi = 2h
    np.multiply(z, half_sd, out=z)
    np.add(z, half_drift[:count], out=z)
    a = work.a[:count]
    np.sin(z, out=a)
    np.cos(z, out=z)
    np.multiply(z, a, out=z)
    np.multiply(a, a, out=a)
    sum_q = np.add.reduce(a, axis=0, dtype=np.float64)
    sum_h = np.add.reduce(z, axis=0, dtype=np.float64)
    if not second:
        return _BlockSums(walk_end, sum_q, sum_h, None, None)
    # sin^2 psi = 4h^2, sin psi cos psi = 2h - 4hq
    np.multiply(a, z, out=a)
    np.multiply(z, z, out=z)
    sum_hq = np.add.reduce(a, axis=0, dtype=np.float64)
    sum_h2 = np.add.reduce(z, axis=0, dtype=np.float64)
    return _BlockSums(walk_end, sum_q, sum_h, sum_hq, sum_h2)


def _heading_sums(
    theta: FloatArray,
    n_segments: int,
    heading_sd: float,
    drift: float,
    rng: np.random.Generator,
    second: bool,
) -> _HeadingSums:
    """Draw the headings of ``n_segments`` segments and sum their cos and sin.

    ``theta`` (rad, float64, shape (m,)) is the real heading before the first
    segment and is advanced in place to the heading after the last. The
    segments are taken in blocks; within a block the heading relative to the
    block start, psi, is small, so it is accurate in float32, and the sums
    are rotated by the float64 block start heading alpha:
    sum cos(alpha + psi) = cos alpha sum cos psi - sin alpha sum sin psi.
    cos psi = 1 - 2 sin^2(psi/2) keeps the small deviations from 1, which
    carry the K_theta decay, from being rounded away in float32.
    """
    m = theta.shape[0]
    n_blocks = -(-n_segments // _SEGMENT_BLOCK)
    rows = -(-n_segments // n_blocks)
    work = _Workspace(rows, m)
    half_drift = _half_drift(drift, rows)
    half_sd = np.float32(0.5 * heading_sd)
    sums = _HeadingSums(np.zeros(m), np.zeros(m), np.zeros(m), np.zeros(m))
    done = 0
    while done < n_segments:
        count = min(rows, n_segments - done)
        block = _block_sums(work, rng, count, half_sd, half_drift, second)
        local_cos = count - 2.0 * block.q
        local_sin = 2.0 * block.h
        cos_a = np.cos(theta)
        sin_a = np.sin(theta)
        sums.cos[:] += cos_a * local_cos - sin_a * local_sin
        sums.sin[:] += sin_a * local_cos + cos_a * local_sin
        if block.hq is not None and block.h2 is not None:
            local_cos2 = count - 8.0 * block.h2
            local_sin2 = 4.0 * block.h - 8.0 * block.hq
            cos_2a = cos_a * cos_a - sin_a * sin_a
            sin_2a = 2.0 * sin_a * cos_a
            sums.cos2[:] += cos_2a * local_cos2 - sin_2a * local_sin2
            sums.sin2[:] += sin_2a * local_cos2 + cos_2a * local_sin2
        theta += heading_sd * block.walk_end + count * drift
        done += count
    return sums


def _add_translation_noise(
    x: FloatArray,
    y: FloatArray,
    sums: _HeadingSums,
    n_segments: int,
    rho_sd: float,
    rng: np.random.Generator,
) -> None:
    """Add sum_i d-rho_i (cos theta_i, sin theta_i), drawn exactly given the headings."""
    c2 = 0.5 * (n_segments + sums.cos2)
    cs = 0.5 * sums.sin2
    s2 = n_segments - c2
    l11 = np.sqrt(np.maximum(c2, 0.0))
    l21 = np.divide(cs, l11, out=np.zeros_like(cs), where=l11 > 0)
    l22 = np.sqrt(np.maximum(s2 - l21 * l21, 0.0))
    z = rng.standard_normal((2, x.shape[0]))
    x += rho_sd * (l11 * z[0])
    y += rho_sd * (l21 * z[0] + l22 * z[1])


def _drive_one(
    x: FloatArray,
    y: FloatArray,
    theta: FloatArray,
    n_segments: int,
    heading_sd: float,
    rho_sd: float,
    drift: float,
    step: float,
    rng: np.random.Generator,
) -> None:
    """:func:`_heading_sums` and :func:`_add_translation_noise` for a single
    trial (the fake robots' calls): the same draws in the same order and the
    same float64 operations one by one, on Python floats instead of arrays of
    one element (IEEE arithmetic rounds each the same way; the cosines still
    come from numpy), so the result is bit for bit the array path's."""
    second = rho_sd > 0.0
    n_blocks = -(-n_segments // _SEGMENT_BLOCK)
    rows = -(-n_segments // n_blocks)
    work = _Workspace(rows, 1)
    half_drift = _half_drift(drift, rows)
    half_sd = np.float32(0.5 * heading_sd)
    heading = float(theta[0])
    sum_cos = sum_sin = sum_cos2 = sum_sin2 = 0.0
    done = 0
    while done < n_segments:
        count = min(rows, n_segments - done)
        block = _block_sums(work, rng, count, half_sd, half_drift, second)
        local_cos = count - 2.0 * float(block.q[0])
        sum_h = float(block.h[0])
        local_sin = 2.0 * sum_h
        cos_a = float(np.cos(heading))
        sin_a = float(np.sin(heading))
        sum_cos += cos_a * local_cos - sin_a * local_sin
        sum_sin += sin_a * local_cos + cos_a * local_sin
        if block.hq is not None and block.h2 is not None:
            local_cos2 = count - 8.0 * float(block.h2[0])
            local_sin2 = 4.0 * sum_h - 8.0 * float(block.hq[0])
            cos_2a = cos_a * cos_a - sin_a * sin_a
            sin_2a = 2.0 * sin_a * cos_a
            sum_cos2 += cos_2a * local_cos2 - sin_2a * local_sin2
            sum_sin2 += sin_2a * local_cos2 + cos_2a * local_sin2
        heading += heading_sd * float(block.walk_end[0]) + count * drift
        done += count
    theta[0] = heading
    end_x = float(x[0]) + step * sum_cos
    end_y = float(y[0]) + step * sum_sin
    if second:
        c2 = 0.5 * (n_segments + sum_cos2)
        cs = 0.5 * sum_sin2
        s2 = n_segments - c2
        l11 = math.sqrt(max(c2, 0.0))
        l21 = cs / l11 if l11 > 0 else 0.0
        l22 = math.sqrt(max(s2 - l21 * l21, 0.0))
        z0, z1 = (float(v) for v in rng.standard_normal(2))
        end_x += rho_sd * (l11 * z0)
        end_y += rho_sd * (l21 * z0 + l22 * z1)
    x[0] = end_x
    y[0] = end_y


def _drive_literal(
    x: FloatArray,
    y: FloatArray,
    theta: FloatArray,
    signed_segment_m: float,
    n_segments: int,
    params: ErrorParameters,
    rng: np.random.Generator,
) -> FloatArray:
    """The model read literally, in float64: a distance noise draw for every segment.

    Slow and memory-hungry; it records the trajectory and is the reference
    the fast path is tested against.
    """
    n = x.shape[0]
    delta = abs(signed_segment_m)
    sign = 1.0 if signed_segment_m > 0 else -1.0
    heading_sd = math.sqrt(params.k_theta * delta)
    rho_sd = math.sqrt(params.k_rho * delta)
    drift = params.e_r * signed_segment_m
    step = (1.0 + params.e_t) * signed_segment_m
    out: FloatArray = np.empty((n, n_segments, 3))
    rows = max(1, _LITERAL_CHUNK_ELEMENTS // n_segments)
    for lo in range(0, n, rows):
        hi = min(n, lo + rows)
        m = hi - lo
        increments = rng.standard_normal((m, n_segments))
        increments *= heading_sd
        increments += drift
        headings = np.cumsum(increments, axis=1)
        headings += theta[lo:hi, None]
        rho = step + sign * rho_sd * rng.standard_normal((m, n_segments))
        out[lo:hi, :, 0] = x[lo:hi, None] + np.cumsum(rho * np.cos(headings), axis=1)
        out[lo:hi, :, 1] = y[lo:hi, None] + np.cumsum(rho * np.sin(headings), axis=1)
        out[lo:hi, :, 2] = headings
        x[lo:hi] = out[lo:hi, -1, 0]
        y[lo:hi] = out[lo:hi, -1, 1]
        theta[lo:hi] = headings[:, -1]
    return out


def simulate(
    path: EncoderPath,
    params: ErrorParameters,
    n_trials: int,
    *,
    seed: SeedLike = None,
    segment_m: float = DEFAULT_SEGMENT_M,
    trajectory: bool = False,
    progress: Callable[[int], None] | None = None,
) -> SimulationResult:
    """Simulate ``n_trials`` independent runs of ``path`` under ``params``.

    Args:
        path: the encoder path.
        params: the odometry error parameters (SI).
        n_trials: number of independent trials.
        seed: an int, a numpy Generator, or None.
        segment_m: largest encoder length of one segment, metres; every leg
            is cut into equal segments no longer than this.
        trajectory: also return every trial's real trajectory.
        progress: called with the number of trials finished so far.

    Returns:
        A :class:`SimulationResult`.
    """
    if n_trials < 1:
        raise ParameterError(f"n_trials must be at least 1, got {n_trials}")
    if not math.isfinite(segment_m) or segment_m <= 0:
        raise ParameterError(f"segment_m must be a positive length, got {segment_m!r}")
    rng = make_rng(seed)
    legs = path.legs
    counts = [segments_per_leg(float(h), segment_m) for h in legs.length_m]
    seg = legs.length_m / np.array(counts, dtype=np.float64)
    n_points = 1 + sum(counts) if trajectory else 0
    batch = n_trials if trajectory else min(n_trials, 4 * _TRIAL_BLOCK)
    poses = np.empty((n_trials, 3))
    traj: FloatArray | None = np.empty((n_trials, n_points, 3)) if trajectory else None
    for lo in range(0, n_trials, batch):
        hi = min(n_trials, lo + batch)
        x = np.zeros(hi - lo)
        y = np.zeros(hi - lo)
        theta = np.zeros(hi - lo)
        if traj is not None:
            traj[lo:hi, 0, :] = 0.0
        point = 1
        for j, count in enumerate(counts):
            # legs carry their own encoder heading, so turns are applied by
            # rotating the real heading by the change of encoder heading
            turn = legs.heading_rad[j] - (legs.heading_rad[j - 1] if j > 0 else 0.0)
            theta += turn
            block = drive_straight(
                x, y, theta, float(legs.sign[j] * seg[j]), count, params, rng, trajectory
            )
            if traj is not None and block is not None:
                traj[lo:hi, point : point + count, :] = block
                point += count
        theta += path.net_turn_rad - float(legs.heading_rad[-1])
        poses[lo:hi, 0] = x
        poses[lo:hi, 1] = y
        poses[lo:hi, 2] = theta - path.winding_rad
        if progress is not None:
            progress(hi)
    return SimulationResult(pose_change=poses, trajectory=traj, segment_m=seg)


@dataclass(frozen=True)
class DiscreteMeans:
    """Exact expectations of the discrete model at a finite segment length.

    Attributes:
        x: <x>, metres.
        y: <y>, metres.
        square_distance: <x^2 + y^2>, square metres.
    """

    x: float
    y: float
    square_distance: float


def discrete_means(path: EncoderPath, params: ErrorParameters, segment_m: float) -> DiscreteMeans:
    """<x>, <y> and <x^2 + y^2> of :func:`simulate` with this ``segment_m``, computed exactly.

    Eq. (28) summed over the segments (with the decay e^{-K_theta s/2}, s the
    distance driven), and its second-moment analogue summed over pairs of
    segments in O(number of segments). Comparing these with the N -> infinity
    closed forms gives the discretisation bias of a segment length.
    Valid while K_theta times the path length is below about 2000 (the pair
    sum scales terms by e^{+-K_theta s/2} about the middle of the path).
    """
    if not math.isfinite(segment_m) or segment_m <= 0:
        raise ParameterError(f"segment_m must be a positive length, got {segment_m!r}")
    legs = path.legs
    sign, delta, heading, signed_end, arc_end = [], [], [], [], []
    for j, length in enumerate(legs.length_m):
        count = segments_per_leg(float(length), segment_m)
        i = np.arange(1, count + 1, dtype=np.float64)
        seg = float(length) / count
        sign.append(np.full(count, legs.sign[j]))
        delta.append(np.full(count, seg))
        heading.append(np.full(count, legs.heading_rad[j]))
        signed_end.append(legs.start_signed_m[j] + legs.sign[j] * seg * i)
        arc_end.append(legs.start_arc_m[j] + seg * i)
    lengths = np.concatenate(delta)
    arc = np.concatenate(arc_end) - 0.5 * path.distance_m
    mean_rho = np.concatenate(sign) * (1.0 + params.e_t) * lengths
    phase = np.exp(1j * (np.concatenate(heading) + params.e_r * np.concatenate(signed_end)))
    half_k = 0.5 * params.k_theta
    # <e^{i theta_l}> = e^{i mean theta_l} e^{-K_theta s_l / 2}
    forward = mean_rho * phase * np.exp(-half_k * (arc + 0.5 * path.distance_m))
    position = complex(forward.sum())
    # pairs k < l: <e^{i(theta_l - theta_k)}> = e^{i(mean_l - mean_k)} e^{-K_theta (s_l - s_k)/2}
    later = mean_rho * phase * np.exp(-half_k * arc)
    earlier = np.cumsum(mean_rho * np.conj(phase) * np.exp(half_k * arc))
    pairs = float(np.sum(later[1:] * earlier[:-1]).real)
    diagonal = float(np.sum(mean_rho**2 + params.k_rho * lengths))
    return DiscreteMeans(x=position.real, y=position.imag, square_distance=diagonal + 2.0 * pairs)
