"""Opening a serial URL, shared by every backend.

``serial.serial_for_url`` takes a device path, a pty, ``socket://``,
``rfc2217://`` and the fakes' URL schemes alike, so every transport goes
through one code path. A backend checks its own baud rates first.
"""

from __future__ import annotations

import termios
from typing import Protocol

import serial

from odohil.errors import ConnectionFailedError

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

    Raises ConnectionFailedError when the port does not open.
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
    except (serial.SerialException, OSError, ValueError) as exc:
        raise ConnectionFailedError(f"cannot open {url!r}: {exc}") from exc
    return port
