"""Synthetic recordings for the log readers' tests: a differential drive
driven by commanded speeds, its odometry integrated from them and its ground
truth from the same speeds with known errors, seen from a world frame."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from odohil.science.paths import FloatArray

WORLD = (2.0, -1.0, 2.9)
"""Where the ground truth's world frame sees the odometry's origin (m, m, rad):
near pi, so that the ground truth's headings wrap."""


@dataclass(frozen=True)
class Motion:
    """Drive at ``v`` m/s and ``w`` rad/s for ``duration_s`` (0, 0: rest)."""

    duration_s: float
    v: float = 0.0
    w: float = 0.0


def rest(duration_s: float = 2.0) -> Motion:
    return Motion(duration_s)


@dataclass(frozen=True)
class SynthLog:
    t_s: FloatArray
    odometry: FloatArray
    truth: FloatArray
    true_changes: list[tuple[float, float, float]]
    """Each motion's true pose change (start frame, heading unwrapped), rests skipped."""


def _integrate(v: FloatArray, w: FloatArray, dt: float) -> FloatArray:
    theta = np.concatenate([[0.0], np.cumsum(w * dt)])
    chord = v * dt * np.sinc(w * dt / (2 * math.pi))
    mid = theta[:-1] + 0.5 * w * dt
    x = np.concatenate([[0.0], np.cumsum(chord * np.cos(mid))])
    y = np.concatenate([[0.0], np.cumsum(chord * np.sin(mid))])
    return np.stack([x, y, theta], axis=1)


def synth_log(
    motions: list[Motion],
    *,
    rate_hz: float = 50.0,
    scale: float = 0.01,
    turn_scale: float = -0.02,
    jitter: tuple[float, float] = (1e-4, 1e-3),
    seed: int = 1,
    t0_s: float = 1000.0,
) -> SynthLog:
    """A log of the motions: the true robot drives ``1 + scale`` times the
    odometry's distance and turns ``1 + turn_scale`` times its angle; the
    ground truth adds white jitter (m, rad) and is seen from :data:`WORLD`."""
    dt = 1.0 / rate_hz
    v_parts, w_parts, labels = [], [], []
    for index, motion in enumerate(motions):
        n = round(motion.duration_s * rate_hz)
        v_parts.append(np.full(n, motion.v))
        w_parts.append(np.full(n, motion.w))
        labels.append(np.full(n, index))
    v, w = np.concatenate(v_parts), np.concatenate(w_parts)
    odo = _integrate(v, w, dt)
    true = _integrate(v * (1 + scale), w * (1 + turn_scale), dt)
    which = np.concatenate([[0], np.concatenate(labels)])
    changes = []
    for index, motion in enumerate(motions):
        if motion.v == 0 and motion.w == 0:
            continue
        rows = np.flatnonzero(which == index)
        a, b = rows[0] - 1, rows[-1]
        c, s = math.cos(true[a, 2]), math.sin(true[a, 2])
        dx, dy = true[b, 0] - true[a, 0], true[b, 1] - true[a, 1]
        changes.append((c * dx + s * dy, -s * dx + c * dy, true[b, 2] - true[a, 2]))
    rng = np.random.default_rng(seed)
    xw, yw, tw = WORLD
    c, s = math.cos(tw), math.sin(tw)
    world = np.stack(
        [
            xw + c * true[:, 0] - s * true[:, 1],
            yw + s * true[:, 0] + c * true[:, 1],
            true[:, 2] + tw,
        ],
        axis=1,
    )
    world[:, :2] += rng.normal(0.0, jitter[0], (len(world), 2))
    world[:, 2] += rng.normal(0.0, jitter[1], len(world))
    world[:, 2] = np.angle(np.exp(1j * world[:, 2]))  # wrapped, as a capture system gives it
    t = t0_s + dt * np.arange(len(odo))
    return SynthLog(t, odo, world, changes)


def varied_motions() -> list[Motion]:
    """A straight run, a spin, a backward run, an arc: each between rests."""
    return [
        rest(),
        Motion(5.0, v=0.2),
        rest(),
        Motion(4.0, w=-0.8),
        rest(),
        Motion(3.0, v=-0.15),
        rest(),
        Motion(8.0, v=0.2, w=0.5),
        rest(),
    ]
