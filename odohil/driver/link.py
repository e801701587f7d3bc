"""One request, one reply, with the host library's timing.

Before each request the link discards pending input (Ndirect's pre-write
drain); then it writes the packet and waits for one reply: the first byte
within ``first_byte_s`` (1 s normally, ``ws`` timeout + 1 s, ``zr`` 120 s),
after which 1 s of silence aborts the reply.
"""

from __future__ import annotations

import contextlib
import termios
import time
from dataclasses import dataclass
from typing import Protocol

import serial

from odohil.errors import (
    ChecksumError,
    ConnectionFailedError,
    DisconnectedError,
    FramingError,
    OdohilTimeoutError,
    ParameterError,
)
from odohil.protocol.framing import DecodeFault, Packet, PacketDecoder

BAUD_RATES = (4800, 9600, 19200, 38400)
DEFAULT_BAUD = 38400
NORMAL_TIMEOUT_S = 1.0
"""First-byte wait for ordinary requests, and the silence that aborts a reply."""
ZR_TIMEOUT_S = 120.0
_IO_ERRORS = (serial.SerialException, OSError, termios.error)
"""What a vanished line raises: EIO from read/write, or from tcflush on a pty."""
READ_SLICE_S = 0.05
"""pyserial read timeout: how often the link checks its own deadlines."""


class Port(Protocol):
    """The part of a pyserial port the link uses."""

    @property
    def in_waiting(self) -> int: ...

    def read(self, size: int = 1) -> bytes: ...

    def write(self, data: bytes, /) -> int | None: ...

    def flush(self) -> None: ...

    def reset_input_buffer(self) -> None: ...

    def close(self) -> None: ...


def open_port(url: str, baud: int = DEFAULT_BAUD) -> Port:
    """Open a serial URL (device path, pty or ``fakerobot://``) 8N1, no flow control.

    Raises ParameterError for a baud rate the Nomad does not support and
    ConnectionFailedError when the port does not open.
    """
    if baud not in BAUD_RATES:
        raise ParameterError(f"baud must be one of {BAUD_RATES}, got {baud}")
    try:
        port: Port = serial.serial_for_url(
            url,
            baudrate=baud,
            bytesize=8,
            parity="N",
            stopbits=1,
            rtscts=False,
            xonxoff=False,
            timeout=READ_SLICE_S,
        )
    except (serial.SerialException, OSError, ValueError) as exc:
        raise ConnectionFailedError(f"cannot open {url!r}: {exc}") from exc
    return port


@dataclass
class LinkStats:
    """Counters of what the link saw (mutable, for diagnostics)."""

    requests: int = 0
    bytes_out: int = 0
    bytes_in: int = 0
    garbage_bytes: int = 0
    drained_bytes: int = 0


_FAULT_ERRORS: dict[str, type[FramingError] | type[ChecksumError]] = {
    "bad_checksum": ChecksumError,
    "bad_end": FramingError,
    "bad_length": FramingError,
}


class Link:
    """Strict request/reply over an open port. Not thread safe."""

    def __init__(self, port: Port, silence_s: float = NORMAL_TIMEOUT_S) -> None:
        self._port = port
        self._decoder = PacketDecoder()
        self._silence_s = silence_s
        self._closed = False
        self.stats = LinkStats()

    @property
    def closed(self) -> bool:
        """Whether :meth:`close` was called."""
        return self._closed

    def close(self) -> None:
        """Close the port (idempotent)."""
        if not self._closed:
            self._closed = True
            with contextlib.suppress(*_IO_ERRORS):
                self._port.close()

    def exchange(self, packet: bytes, first_byte_s: float = NORMAL_TIMEOUT_S) -> Packet:
        """Send one whole packet and return the reply packet.

        Garbage before the reply (bytes without a start byte) is skipped and
        counted; a bad frame raises ChecksumError or FramingError at once
        (CHOICE C17). Raises OdohilTimeoutError when no byte arrives within
        ``first_byte_s`` seconds, or the reply stalls for 1 s; DisconnectedError
        when the port is closed or fails (EIO).
        """
        if self._closed:
            raise DisconnectedError("the link is closed")
        try:
            self._drain()
            self._port.write(packet)
            self._port.flush()
        except _IO_ERRORS as exc:
            raise DisconnectedError(f"serial line failed: {exc}") from exc
        self.stats.requests += 1
        self.stats.bytes_out += len(packet)
        return self._read_reply(first_byte_s)

    def _drain(self) -> None:
        self._decoder.reset()
        self._port.reset_input_buffer()
        while waiting := self._port.in_waiting:
            self.stats.drained_bytes += len(self._port.read(waiting))

    def _read_reply(self, first_byte_s: float) -> Packet:
        start = time.monotonic()
        last_byte: float | None = None
        while True:
            try:
                data = self._port.read(max(self._decoder.missing, self._port.in_waiting))
            except _IO_ERRORS as exc:
                raise DisconnectedError(f"serial read failed: {exc}") from exc
            now = time.monotonic()
            if data:
                last_byte = now
                self.stats.bytes_in += len(data)
                for event in self._decoder.feed(data):
                    if isinstance(event, Packet):
                        return event
                    self._fault(event)
            elif last_byte is None:
                if now - start >= first_byte_s:
                    raise OdohilTimeoutError(f"no reply within {first_byte_s:g} s")
            elif now - last_byte >= self._silence_s:
                pending = self._decoder.reset()
                raise OdohilTimeoutError(
                    f"reply stalled after {len(pending)} bytes: {pending[:16].hex(' ')}"
                )

    def _fault(self, fault: DecodeFault) -> None:
        if fault.kind == "garbage":
            self.stats.garbage_bytes += len(fault.data)
            return
        self._decoder.reset()
        raise _FAULT_ERRORS[fault.kind](
            f"{fault.kind.replace('_', ' ')} in reply: {fault.data[:16].hex(' ')}"
        )
