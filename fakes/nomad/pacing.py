"""Byte pacing at a serial line rate: 10 bit times per byte (8N1)."""

from __future__ import annotations

import math

DEFAULT_BAUD = 38400
"""The Ndirect 2.7 default line rate (CHOICE C1)."""


class LinePacer:
    """Releases queued bytes no faster than ``baud`` / 10 bytes per second.

    A byte is released when its last bit would have arrived. With
    ``baud=None`` every byte is released at once.
    """

    def __init__(self, baud: int | None) -> None:
        self.byte_s = 10.0 / baud if baud else 0.0
        self._queue = bytearray()
        self._free_at = -math.inf

    @property
    def pending(self) -> int:
        """Bytes queued and not yet released."""
        return len(self._queue)

    def push(self, data: bytes, now: float) -> None:
        """Queue ``data`` for transmission at wall time ``now`` s."""
        if not self._queue:
            self._free_at = max(self._free_at, now)
        self._queue += data

    def release(self, now: float) -> bytes:
        """The bytes that have fully crossed the line by ``now``."""
        if not self._queue:
            return b""
        if self.byte_s == 0.0:
            n = len(self._queue)
        else:
            n = min(len(self._queue), int((now - self._free_at) / self.byte_s))
            if n <= 0:
                return b""
            self._free_at += n * self.byte_s
        out = bytes(self._queue[:n])
        del self._queue[:n]
        return out

    def next_release(self) -> float | None:
        """Wall time at which the next queued byte will have arrived, or None."""
        if not self._queue:
            return None
        return self._free_at + self.byte_s

    def clear(self) -> None:
        """Drop everything queued."""
        self._queue.clear()
