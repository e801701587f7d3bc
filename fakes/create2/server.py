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
"""

from __future__ import annotations

import array
import contextlib
import fcntl
import termios
from collections.abc import Callable
from pathlib import Path
from typing import Any, cast

from fakes.create2.engine import Create2Engine
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


class Create2PtyServer(PtyServer):
    """A :class:`PtyServer` for a :class:`Create2Engine` (module docstring)."""

    def __init__(self, engine: Create2Engine, baud: int, pacing: bool, truth_path: Path) -> None:
        super().__init__(cast(Any, engine), baud, pacing, truth_path)
        self.create2 = engine

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
