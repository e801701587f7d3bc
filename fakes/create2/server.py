"""Serve one fake Create 2 on a pseudo-terminal, with its truth socket beside it.

The fake Nomad's pty server (fakes/nomad/server.py) carries any engine with
its interface; this one adds the test hook of the truth socket (a line
``event NAME`` injects a safety event before the snapshot is sent) and the
host's line rate: a pty carries no baud rate, but the speed a host sets on its
end with tcsetattr (pyserial does, on open and on every change of
``baudrate``) is kept by the tty, so the server reads it from its own handle
on the same tty and tells the engine (C1). The pty starts at the robot's
rate, so a host that never sets a speed talks at it; output is paced at the
robot's current rate (the Baud command changes it).

The host's reads bound the motion clock (``Create2Engine(host_bound_s=...)``,
fakes/create2/clock.py ``ReadBoundClock``): every byte handed to the pty is
logged with its wall time; the bytes the host has not read are those still on
the tty's input queue (FIONREAD on the server's handle of the same tty) and
those the full pty could not take yet, so the host has read everything written
up to the wall time of the newest chunk it has read whole, or up to now when
nothing is left unread. Each pump tells the engine that instant.
"""

from __future__ import annotations

import array
import contextlib
import fcntl
import termios
from collections import deque
from collections.abc import Callable
from pathlib import Path
from typing import Any, cast

from fakes.create2.engine import Create2Engine
from fakes.nomad.pacing import LinePacer
from fakes.nomad.server import PtyServer, serve_until_signalled
from odohil.errors import ParameterError

TCGETS2 = 0x802C542A
"""Linux ioctl reading ``struct termios2``, whose c_ospeed is the speed in baud
(the same request pyserial uses to set rates without a B constant)."""
_SPEEDS = {
    getattr(termios, f"B{rate}"): rate
    for rate in (300, 600, 1200, 2400, 4800, 9600, 19200, 38400, 57600, 115200)
}


def tty_speed(fd: int) -> int | None:
    """The output speed of the tty open on ``fd``, baud (None when unknown)."""
    buf = array.array("i", [0] * 64)
    with contextlib.suppress(OSError):
        fcntl.ioctl(fd, TCGETS2, buf)
        if buf[10] > 0:
            return int(buf[10])
    with contextlib.suppress(termios.error, OSError):
        return _SPEEDS.get(termios.tcgetattr(fd)[5])
    return None


def unread_bytes(fd: int) -> int | None:
    """Bytes waiting to be read on the tty open on ``fd`` (None when unknown)."""
    buf = array.array("i", [0])
    try:
        fcntl.ioctl(fd, termios.FIONREAD, buf)
    except OSError:
        return None
    return int(buf[0])


class _LoggedPacer(LinePacer):
    """A :class:`LinePacer` that logs what it releases to the pty: the
    running byte total after each release, and the release's wall time."""

    def __init__(self, baud: int | None) -> None:
        super().__init__(baud)
        self.released = 0
        self.log: deque[tuple[int, float]] = deque()

    def release(self, now: float) -> bytes:
        out = super().release(now)
        if out:
            self.released += len(out)
            self.log.append((self.released, now))
        return out


class Create2PtyServer(PtyServer):
    """A :class:`PtyServer` for a :class:`Create2Engine` (module docstring)."""

    def __init__(self, engine: Create2Engine, baud: int, pacing: bool, truth_path: Path) -> None:
        super().__init__(cast(Any, engine), baud, pacing, truth_path)
        self.create2 = engine
        self._log = _LoggedPacer(baud if pacing else None)
        self.pacer = self._log
        self._seen = engine.wall0
        """The host has read everything written up to this wall time, s."""

    def start(self) -> None:
        """Open the pty at the robot's rate, and the truth socket."""
        super().start()
        assert self._slave is not None
        constant = getattr(termios, f"B{self.create2.baud}", None)
        if constant is not None:
            attrs = termios.tcgetattr(self._slave)
            attrs[4] = attrs[5] = constant
            termios.tcsetattr(self._slave, termios.TCSANOW, attrs)

    def _pump(self, now: float) -> None:
        if self._slave is not None:
            self.create2.host_baud = tty_speed(self._slave)
        byte_s = 10.0 / self.create2.baud
        for pacer in (self.pacer, self.inbound):
            if pacer.byte_s:
                pacer.byte_s = byte_s
        super()._pump(now)
        self._note_reads(now)

    def _note_reads(self, now: float) -> None:
        """Tell the engine up to when the host has read everything (module docstring)."""
        if self._slave is None:
            return
        unread = (unread_bytes(self._slave) or 0) + len(self._unwritten)
        read_upto = self._log.released - unread
        log = self._log.log
        while log and log[0][0] <= read_upto:
            self._seen = max(self._seen, log.popleft()[1])
        if unread == 0:
            self._seen = now
        self.create2.host_read(self._seen, now)

    def _truth_reply(self, line: str) -> str:
        words = line.split()
        if len(words) == 2 and words[0] == "event":
            # an unknown event injects nothing; the reply is the state as it is
            with contextlib.suppress(ParameterError):
                self.create2.event(words[1])
        return self.create2.truth().to_json()


def serve(
    engine: Create2Engine,
    *,
    baud: int,
    pacing: bool,
    truth_path: Path,
    on_ready: Callable[[str, str], None],
) -> None:
    """Run a :class:`Create2PtyServer` until SIGINT or SIGTERM; ``on_ready(device, socket)``."""
    serve_until_signalled(Create2PtyServer(engine, baud, pacing, truth_path), on_ready)
