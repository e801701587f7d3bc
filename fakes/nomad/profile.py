"""Trapezoidal motion profiles of one axis (pure arithmetic, no clock of its own).

Positions are in wire units (0.1 inch or 0.1 degree), velocities in wire units
per second, accelerations in wire units per second squared, times in simulated
seconds. A profile is a list of constant-acceleration phases that starts from a
known position and velocity; evaluating it at any time is exact, so a motion
ends on its target to the last bit however coarsely the robot is ticked.
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class Phase:
    """A span of constant acceleration.

    Attributes:
        duration_s: length of the phase, s (``math.inf`` for an open-ended cruise).
        accel: acceleration during the phase, wire units/s^2.
    """

    duration_s: float
    accel: float


@dataclass(frozen=True)
class Profile:
    """A planned motion of one axis.

    Attributes:
        t0: simulated start time, s.
        p0: position at ``t0``, wire units.
        v0: velocity at ``t0``, wire units/s.
        phases: the constant-acceleration phases, in order.
        target: for a position move the exact final position (wire units);
            None for velocity or stopping profiles.
    """

    t0: float
    p0: float
    v0: float
    phases: tuple[Phase, ...]
    target: float | None = None

    @property
    def end_time(self) -> float:
        """Simulated time at which the profile ends, s (inf for an endless cruise)."""
        return self.t0 + sum(phase.duration_s for phase in self.phases)

    def at(self, t: float) -> tuple[float, float, bool]:
        """Position (wire), velocity (wire/s) and whether the profile has ended, at time ``t`` s."""
        if t >= self.end_time:
            if self.target is not None:
                return self.target, 0.0, True
            p, v = self._integrate(math.inf)
            return p, v, True
        p, v = self._integrate(t - self.t0)
        return p, v, False

    def _integrate(self, elapsed: float) -> tuple[float, float]:
        p, v = self.p0, self.v0
        for phase in self.phases:
            dt = min(phase.duration_s, elapsed)
            if dt <= 0.0:
                break
            p += v * dt + 0.5 * phase.accel * dt * dt
            v += phase.accel * dt
            elapsed -= dt
        return p, v


def _sign(value: float) -> float:
    return 1.0 if value > 0 else -1.0 if value < 0 else 0.0


def plan_move(p0: float, v0: float, target: float, vmax: float, amax: float) -> tuple[Phase, ...]:
    """Time-optimal trapezoid from (p0, v0) to rest at ``target`` within ``vmax`` and ``amax``.

    Starting while moving is allowed: the axis first brakes (to ``vmax`` if it
    is faster, to rest if it moves away from the target or cannot stop in
    time) and then runs a trapezoid (a triangle if the distance is short).
    ``vmax`` and ``amax`` must be positive.
    """
    phases: list[Phase] = []
    p, v = p0, v0
    for _ in range(4):
        d = target - p
        if v != 0.0:
            s_v = _sign(v)
            if abs(v) > vmax and s_v * d > 0:
                dt = (abs(v) - vmax) / amax
                phases.append(Phase(dt, -s_v * amax))
                p += s_v * (v * v - vmax * vmax) / (2.0 * amax)
                v = s_v * vmax
                continue
            if s_v * d < v * v / (2.0 * amax):
                phases.append(Phase(abs(v) / amax, -s_v * amax))
                p += s_v * v * v / (2.0 * amax)
                v = 0.0
                continue
        if d == 0.0:
            break
        s = _sign(d)
        u = abs(v)
        dd = abs(d)
        vp = min(vmax, math.sqrt(amax * dd + 0.5 * u * u))
        cruise = max(0.0, dd - (vp * vp - u * u) / (2.0 * amax) - vp * vp / (2.0 * amax))
        phases.append(Phase((vp - u) / amax, s * amax))
        if cruise > 0.0:
            phases.append(Phase(cruise / vp, 0.0))
        phases.append(Phase(vp / amax, -s * amax))
        break
    return tuple(phase for phase in phases if phase.duration_s > 0.0)


def plan_velocity(v0: float, v_target: float, amax: float) -> tuple[Phase, ...]:
    """Ramp from ``v0`` to ``v_target`` at ``amax``, then cruise (unless the target is 0)."""
    phases: list[Phase] = []
    dv = v_target - v0
    if dv != 0.0:
        phases.append(Phase(abs(dv) / amax, _sign(dv) * amax))
    if v_target != 0.0:
        phases.append(Phase(math.inf, 0.0))
    return tuple(phases)


def move_duration(distance: float, vmax: float, amax: float) -> float:
    """Duration of a move of ``distance`` from rest to rest, s (trapezoid or triangle)."""
    d = abs(distance)
    if d == 0.0:
        return 0.0
    if vmax * vmax / amax >= d:
        return 2.0 * math.sqrt(d / amax)
    return d / vmax + vmax / amax
