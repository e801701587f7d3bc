"""Clocks that keep a fake's motion from running ahead of a host that is away.

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

On a pty the fake runs on its own and cannot tell a host that is away from
one that is waiting, except by what the host has left unread:
:class:`ReadBoundClock` holds the motion once the host is ``bound_s`` behind
in reading (fakes/create2/server.py measures it).
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


class ReadBoundClock:
    """Motion seconds that run at most ``bound_s`` past what the host has read.

    The pty fake's host reads what the fake wrote (stream frames, replies)
    in its own time; a host that a busy machine starves reads nothing while
    the wheels, on a wall clock, drive on. This clock runs at wall rate until
    ``bound_s`` after the newest wall instant up to which the host has read
    everything (:meth:`host_read`), then holds: a starved host wakes to find
    the wheels at most ``bound_s`` (times the time scale) of driving past
    where its last reading showed them, and the leg ends late instead of
    long. A host with nothing left to read is up to date, whatever it does.

    Args:
        bound_s: how far the motion runs past the host's reading, wall s (> 0).
        start: wall time of motion second 0, s.

    Attributes:
        bound_s: as given.
    """

    def __init__(self, bound_s: float, start: float) -> None:
        if not bound_s > 0:
            raise ValueError(f"bound_s must be positive, got {bound_s!r}")
        self.bound_s = bound_s
        self._start = start
        self._at = start
        self._value = 0.0
        self._until = start + bound_s

    def __call__(self, wall: float) -> float:
        """Motion seconds at wall time ``wall`` (s; not before the last :meth:`host_read`)."""
        return self._value + max(0.0, min(wall, self._until) - self._at)

    def host_read(self, seen: float, now: float) -> None:
        """At wall time ``now`` the host has read everything written up to wall
        time ``seen`` (``now`` when nothing is left unread): the motion may run
        until ``seen + bound_s``."""
        if now > self._at:
            self._value = self(now)
            self._at = now
        self._until = max(self._until, seen + self.bound_s)

    def lost_s(self, wall: float) -> float:
        """Wall seconds the motion has been held so far, at wall time ``wall``."""
        return (wall - self._start) - self(wall)
