"""A wall clock for a fake in process that skips the time its host was away.

An in-process fake runs only when the host calls it (fakes/protocol_fakerobot.py).
When a busy machine deschedules the host for 50 ms, a wall clock lets the fake's
wheels drive through those 50 ms (at a high time scale, centimetres) before the
host can read a frame and send its stop: a leg ends long for a reason no real
robot shares with its host. :class:`LagAbsorbingClock` cuts every gap between
two readings to at most ``max_gap_s``: the fake's time, and so its simulated
motion, advances in bounded steps between host calls, however late they come.

:meth:`LagAbsorbingClock.skip` moves the clock forward without waiting: a port
whose host waits for the fake's next write (``skip_waits=1`` on a
``fakecreate2://`` URL, fakes/protocol_fakerobot.py) jumps to it instead of
sleeping, so the fake runs as fast as its host computes. What the host sees is
the same frames at the same simulated times; only the wall time between them
is gone.
"""

from __future__ import annotations

import time
from collections.abc import Callable


class LagAbsorbingClock:
    """Monotonic seconds in which no two readings are more than ``max_gap_s`` apart.

    Args:
        max_gap_s: longest advance between two readings, s (positive).
        wall: the underlying monotonic clock, s.

    Attributes:
        lost_s: wall time dropped so far, s.
        skipped_s: time added by :meth:`skip` so far, s.
    """

    def __init__(self, max_gap_s: float, wall: Callable[[], float] = time.monotonic) -> None:
        if not max_gap_s > 0:
            raise ValueError(f"max_gap_s must be positive, got {max_gap_s!r}")
        self.max_gap_s = max_gap_s
        self._wall = wall
        self._last = wall()
        self.lost_s = 0.0
        self.skipped_s = 0.0

    def __call__(self) -> float:
        now = self._wall()
        gap = now - self._last
        if gap > self.max_gap_s:
            self.lost_s += gap - self.max_gap_s
        self._last = now
        return now - self.lost_s + self.skipped_s

    def skip(self, seconds: float) -> None:
        """Move the clock ``seconds`` (>= 0, s) forward at once, as if the host
        had slept that long (and no gap bound had cut it)."""
        if seconds > 0:
            self.skipped_s += seconds
