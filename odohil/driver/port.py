"""Opening a serial URL, shared by every backend.

``serial.serial_for_url`` takes a device path, a pty, ``socket://``,
``rfc2217://`` and the fakes' URL schemes alike, so every transport goes
through one code path. A backend checks its own baud rates first.

A URL handler that refuses one of its URL's options (an unknown one, a value
of the wrong kind) raises :class:`~odohil.errors.PortOptionError` from its
``open``; ``serial_for_url`` passes it through (it opens the port it made and
catches nothing), and :func:`open_serial_url` keeps it, a ParameterError (bad
input: exit 2), where a port that does not open is a ConnectionFailedError
(exit 1). No handler is named here.
"""

from __future__ import annotations

import termios
from typing import Protocol

import serial

from odohil.errors import ConnectionFailedError, PortOptionError

IO_ERRORS = (serial.SerialException, OSError, termios.error)
"""What a vanished line raises: EIO from read/write, or from tcflush on a pty."""
READ_SLICE_S = 0.05
"""pyserial read timeout: how often a link checks its own deadlines, s."""


class Port(Protocol):
    """The part of a pyserial port a link uses."""

    @property
    def in_waiting(self) -> int: ...

    def read(self, size: int = 1) -> bytes: ...

    def write(self, data: bytes, /) -> int | None: ...

    def flush(self) -> None: ...

    def reset_input_buffer(self) -> None: ...

    def close(self) -> None: ...


def open_serial_url(url: str, baud: int, read_timeout_s: float = READ_SLICE_S) -> Port:
    """Open a serial URL (device path, pty, ``socket://``, a fake's scheme)
    8N1 without flow control, reads returning after ``read_timeout_s``.

    Raises ConnectionFailedError when the port does not open, and
    PortOptionError when its URL handler refuses an option of the URL.
    """
    try:
        port: Port = serial.serial_for_url(
            url,
            baudrate=baud,
            bytesize=8,
            parity="N",
            stopbits=1,
            rtscts=False,
            xonxoff=False,
            timeout=read_timeout_s,
        )
    except PortOptionError as exc:
        raise PortOptionError(f"cannot open {url!r}: {exc}") from exc
    except (serial.SerialException, OSError, ValueError) as exc:
        raise ConnectionFailedError(f"cannot open {url!r}: {exc}") from exc
    return port


def no_answer(robot: str, url: str, baud: int, detail: str, check: str) -> ConnectionFailedError:
    """The one error of every backend for a port that opens but whose robot
    does not answer at connect time (every command exits 1 on it,
    odohil/cli/exit_codes.py): it names the robot, the port and its rate,
    what went unanswered (``detail``), and what to check (``check``)."""
    return ConnectionFailedError(
        f"the {robot} on {url} does not answer at {baud} baud ({detail}); check {check}"
    )


def port_name(port: object, url: str = "") -> str:
    """``url``, else what the open port says it was opened from."""
    return url or str(getattr(port, "portstr", "") or getattr(port, "port", "") or "the port")


def vouches_idle(port: object) -> bool:
    """Whether the port vouches that no byte is on its way to us now.

    A real line cannot know what is in flight, so this is False for it, and
    a link waits for a quiet line by the clock. A peer in this process (the
    fakes' URL handlers) knows: it says ``idle`` when nothing is queued on
    its line or scheduled to be written, and a quiet wait can end at once.
    """
    return getattr(port, "idle", False) is True


def listens_at_open(port: object) -> bool:
    """Whether the peer listens from the moment the port opens (a peer in
    this process says ``listens_at_open``); a real robot is given its
    documented wait after open."""
    return getattr(port, "listens_at_open", False) is True
