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
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from odohil.errors import ParameterError
from odohil.science.parameters import ErrorParameters
from odohil.science.paths import EncoderPath, FloatArray

DEFAULT_SEGMENT_M = 0.001
"""Default encoder length of one segment, metres."""

_CHUNK_ELEMENTS = 1 << 18

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
    in place (arrays of one shape (n,)). This is the one implementation of the
    discrete model: the batch simulator and the fake robot's physics both call
    it. With ``trajectory=True`` it draws the translation noise segment by
    segment and returns the poses after each segment, shape (n, n_segments, 3).
    """
    if n_segments <= 0:
        return np.empty((x.shape[0], 0, 3)) if trajectory else None
    n = x.shape[0]
    delta = abs(signed_segment_m)
    sign = 1.0 if signed_segment_m > 0 else -1.0
    heading_sd = math.sqrt(params.k_theta * delta)
    rho_sd = math.sqrt(params.k_rho * delta)
    drift = params.e_r * signed_segment_m
    step = (1.0 + params.e_t) * signed_segment_m
    out: FloatArray | None = np.empty((n, n_segments, 3)) if trajectory else None
    rows = max(1, _CHUNK_ELEMENTS // n_segments)
    for lo in range(0, n, rows):
        hi = min(n, lo + rows)
        m = hi - lo
        increments = rng.standard_normal((m, n_segments))
        increments *= heading_sd
        increments += drift
        headings = np.cumsum(increments, axis=1)
        headings += theta[lo:hi, None]
        cos = np.cos(headings)
        sin = np.sin(headings)
        if trajectory:
            assert out is not None
            rho = step + sign * rho_sd * rng.standard_normal((m, n_segments))
            out[lo:hi, :, 0] = x[lo:hi, None] + np.cumsum(rho * cos, axis=1)
            out[lo:hi, :, 1] = y[lo:hi, None] + np.cumsum(rho * sin, axis=1)
            out[lo:hi, :, 2] = headings
            x[lo:hi] = out[lo:hi, -1, 0]
            y[lo:hi] = out[lo:hi, -1, 1]
        else:
            x[lo:hi] += step * cos.sum(axis=1)
            y[lo:hi] += step * sin.sum(axis=1)
            if rho_sd > 0.0:
                _add_translation_noise(x[lo:hi], y[lo:hi], cos, sin, rho_sd, rng)
        theta[lo:hi] = headings[:, -1]
    return out


def _add_translation_noise(
    x: FloatArray,
    y: FloatArray,
    cos: FloatArray,
    sin: FloatArray,
    rho_sd: float,
    rng: np.random.Generator,
) -> None:
    """Add sum_i d-rho_i (cos theta_i, sin theta_i), drawn exactly given the headings."""
    c2 = np.einsum("ij,ij->i", cos, cos)
    cs = np.einsum("ij,ij->i", cos, sin)
    s2 = cos.shape[1] - c2
    l11 = np.sqrt(c2)
    l21 = np.divide(cs, l11, out=np.zeros_like(cs), where=l11 > 0)
    l22 = np.sqrt(np.maximum(s2 - l21 * l21, 0.0))
    z = rng.standard_normal((2, x.shape[0]))
    x += rho_sd * (l11 * z[0])
    y += rho_sd * (l21 * z[0] + l22 * z[1])


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
    batch = n_trials if trajectory else max(1, min(n_trials, (4 * _CHUNK_ELEMENTS) // 64))
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
