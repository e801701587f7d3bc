"""One request, one reply, with the host library's timing, and bounded waits.

Before each request the link waits for a quiet line: it drains what arrives
until no byte has come for :func:`quiet_interval_s` (a few byte times), within
at most ``quiet_total_s`` in all, so a stray or late packet still on its way
is discarded rather than taken for the next reply. Then it writes the packet
and waits for one reply: its start byte within ``first_byte_s`` (1 s
normally, ``ws`` timeout + 1 s, ``zr`` 120 s); bytes without a start byte do
not count as a reply. Once a reply has begun, 1 s of silence aborts it, and
the whole reply must be in within ``first_byte_s + silence_s`` of the
request: no stream of bytes can make a read wait longer.
"""

from __future__ import annotations

import contextlib
import math
import time
from collections.abc import Callable
from dataclasses import dataclass

from odohil.driver.port import IO_ERRORS, Port, open_serial_url, vouches_idle
from odohil.errors import (
    ChecksumError,
    DisconnectedError,
    FramingError,
    OdohilTimeoutError,
    ParameterError,
)
from odohil.protocol.nomad.codes import Code
from odohil.protocol.nomad.framing import DecodeFault, Packet, PacketDecoder

BAUD_RATES = (4800, 9600, 19200, 38400)
DEFAULT_BAUD = 38400
NORMAL_TIMEOUT_S = 1.0
"""First-byte wait for ordinary requests, and the silence that aborts a reply."""
ZR_TIMEOUT_S = 120.0
QUIET_BYTES = 3
"""A line is quiet when no byte has come for this many byte times..."""
QUIET_MIN_S = 0.0005
"""...and for at least this long, s (scheduling jitter of a host and a pty)."""
QUIET_TOTAL_S = NORMAL_TIMEOUT_S
"""Longest wait for a quiet line before a request, s."""
NAK_GRACE_S = 0.25
"""After a NAK, how long the link still waits for a real reply, s: a stray NAK
(a packet that answers nothing) that slipped past the quiet wait is followed
at once by the real reply, a true NAK by silence."""
_SAMPLE_BYTES = 24
"""How many foreign bytes an error message quotes."""


def quiet_interval_s(baud: int) -> float:
    """The silence (s) that makes a line at ``baud`` quiet: :data:`QUIET_BYTES`
    byte times (10 bits each, 8N1), at least :data:`QUIET_MIN_S`."""
    return max(QUIET_MIN_S, QUIET_BYTES * 10.0 / baud)


def open_port(url: str, baud: int = DEFAULT_BAUD) -> Port:
    """Open a serial URL (device path, pty or ``fakerobot://``) for a Nomad:
    8N1, no flow control.

    Raises ParameterError for a baud rate the Nomad does not support and
    ConnectionFailedError when the port does not open.
    """
    if baud not in BAUD_RATES:
        raise ParameterError(f"baud must be one of {BAUD_RATES}, got {baud}")
    return open_serial_url(url, baud)


@dataclass
class LinkStats:
    """Counters of what the link saw (mutable, for diagnostics)."""

    requests: int = 0
    bytes_out: int = 0
    bytes_in: int = 0
    garbage_bytes: int = 0
    drained_bytes: int = 0
    rejected_replies: int = 0


_FAULT_ERRORS: dict[str, type[FramingError] | type[ChecksumError]] = {
    "bad_checksum": ChecksumError,
    "bad_end": FramingError,
    "bad_length": FramingError,
}


class Link:
    """Strict request/reply over an open port. Not thread safe.

    Args:
        port: the open port.
        silence_s: silence that aborts a reply once it has begun, s.
        name: the port's name for messages (default: the port's own, if any).
        quiet_s: silence that makes the line quiet before a request, s
            (default: :func:`quiet_interval_s` at the port's baud rate).
        quiet_total_s: longest wait for a quiet line, s.
    """

    def __init__(
        self,
        port: Port,
        silence_s: float = NORMAL_TIMEOUT_S,
        *,
        name: str | None = None,
        quiet_s: float | None = None,
        quiet_total_s: float = QUIET_TOTAL_S,
    ) -> None:
        self._port = port
        self._decoder = PacketDecoder()
        self._silence_s = silence_s
        self._name = name or str(getattr(port, "port", None) or getattr(port, "name", "the port"))
        baud = getattr(port, "baudrate", DEFAULT_BAUD)
        self._quiet_s = quiet_interval_s(
            baud if isinstance(baud, int) and baud > 0 else DEFAULT_BAUD
        )
        if quiet_s is not None:
            self._quiet_s = quiet_s
        self._quiet_total_s = quiet_total_s
        self._last_rx = time.monotonic()  # the first request, too, waits for quiet
        self._closed = False
        self.stats = LinkStats()

    @property
    def name(self) -> str:
        """The port's name, as error messages give it."""
        return self._name

    @property
    def quiet_s(self) -> float:
        """The silence before a request that makes the line quiet, s."""
        return self._quiet_s

    @property
    def closed(self) -> bool:
        """Whether :meth:`close` was called."""
        return self._closed

    def close(self) -> None:
        """Close the port (idempotent)."""
        if not self._closed:
            self._closed = True
            with contextlib.suppress(*IO_ERRORS):
                self._port.close()

    def exchange(
        self,
        packet: bytes,
        first_byte_s: float = NORMAL_TIMEOUT_S,
        accept: Callable[[Packet], bool] | None = None,
    ) -> Packet:
        """Wait for a quiet line, send one whole packet and return the reply packet.

        Garbage before the reply (bytes without a start byte) is skipped and
        counted, but does not count as a reply; a bad frame raises
        ChecksumError or FramingError at once (CHOICE C17). A NAK is returned
        only if no other reply follows within :data:`NAK_GRACE_S` (else it was
        a stray packet and is discarded). A well-formed packet
        for which ``accept`` returns False (a stale reply) is discarded and the
        wait goes on, within the same deadline. Raises OdohilTimeoutError when
        the line does not fall quiet within ``quiet_total_s``, no reply begins
        within ``first_byte_s`` seconds, a reply stalls for ``silence_s``, or
        the whole reply is not in within ``first_byte_s + silence_s``; the
        message names the port and quotes bytes that are not the robot's
        protocol. DisconnectedError when the port is closed or fails (EIO).
        """
        if self._closed:
            raise DisconnectedError("the link is closed")
        try:
            self._wait_quiet()
            self._port.write(packet)
            self._port.flush()
        except IO_ERRORS as exc:
            raise DisconnectedError(f"serial line {self._name} failed: {exc}") from exc
        self.stats.requests += 1
        self.stats.bytes_out += len(packet)
        return self._read_reply(first_byte_s, accept)

    def _wait_quiet(self) -> None:
        """Drain until no byte has come for ``quiet_s`` (at most ``quiet_total_s``),
        or until the port vouches that no byte is on its way (a peer in process:
        odohil/driver/port.py's :func:`vouches_idle`; never a real line)."""
        self._decoder.reset()
        start = time.monotonic()
        drained = bytearray()
        while True:
            while waiting := self._port.in_waiting:
                data = self._port.read(waiting)
                self.stats.drained_bytes += len(data)
                if len(drained) < _SAMPLE_BYTES:
                    drained += data
                self._last_rx = time.monotonic()
            now = time.monotonic()
            quiet_for = now - self._last_rx
            if quiet_for >= self._quiet_s or vouches_idle(self._port):
                return
            if now - start >= self._quiet_total_s:
                raise OdohilTimeoutError(
                    f"{self._name} never fell quiet for {self._quiet_s * 1000:.1f} ms within "
                    f"{self._quiet_total_s:g} s: the line carries bytes that are not the "
                    f"robot's protocol ({_quote(bytes(drained))}); is this the robot's port?"
                )
            time.sleep(min(self._quiet_s - quiet_for, self._quiet_total_s - (now - start)))

    def _read_reply(self, first_byte_s: float, accept: Callable[[Packet], bool] | None) -> Packet:
        start = time.monotonic()
        begin_by = start + first_byte_s
        deadline = begin_by + self._silence_s
        last_byte: float | None = None
        foreign = bytearray()
        n_foreign = 0
        nak: Packet | None = None
        nak_until = math.inf
        rejected = self.stats.rejected_replies
        while True:
            try:
                data = self._port.read(max(self._decoder.missing, self._port.in_waiting))
            except IO_ERRORS as exc:
                raise DisconnectedError(f"serial read on {self._name} failed: {exc}") from exc
            now = time.monotonic()
            if data:
                self._last_rx = now
                self.stats.bytes_in += len(data)
                for event in self._decoder.feed(data):
                    if isinstance(event, Packet):
                        if accept is not None and not accept(event):
                            self.stats.rejected_replies += 1
                        elif event.type == Code.NAK and nak is None:
                            nak, nak_until = event, min(begin_by, now + NAK_GRACE_S)
                        else:
                            if nak is not None:
                                self.stats.rejected_replies += 1
                            return event
                        continue
                    if event.kind == "garbage":
                        self.stats.garbage_bytes += len(event.data)
                        n_foreign += len(event.data)
                        if len(foreign) < _SAMPLE_BYTES:
                            foreign += event.data
                        continue
                    self._fault(event)
                if self._decoder.pending:
                    last_byte = now
            begun = self._decoder.pending > 0
            if nak is not None and not begun and now >= nak_until:
                return nak
            if not begun and now >= begin_by:
                message = self._no_reply(first_byte_s, n_foreign, bytes(foreign))
                if self.stats.rejected_replies > rejected:
                    message += (
                        f"; {self.stats.rejected_replies - rejected} repl(ies) discarded as not "
                        "this request's (a reply to another request, or a robot timestamp older "
                        "than the last reply's)"
                    )
                raise OdohilTimeoutError(message)
            if begun and last_byte is not None and now - last_byte >= self._silence_s:
                pending = self._decoder.reset()
                raise OdohilTimeoutError(
                    f"reply on {self._name} stalled after {len(pending)} bytes: "
                    f"{pending[:16].hex(' ')}"
                )
            if now >= deadline:
                pending = self._decoder.reset()
                raise OdohilTimeoutError(
                    f"reply on {self._name} incomplete after {now - start:.1f} s "
                    f"({len(pending)} bytes: {pending[:16].hex(' ')})"
                )

    def _no_reply(self, first_byte_s: float, n_foreign: int, sample: bytes) -> str:
        text = f"no reply within {first_byte_s:g} s on {self._name}"
        if n_foreign:
            text += (
                f"; {n_foreign} bytes arrived that are not the robot's protocol "
                f"(no 0x01 start byte: {_quote(sample)}); is this the robot's port?"
            )
        return text

    def _fault(self, fault: DecodeFault) -> None:
        self._decoder.reset()
        raise _FAULT_ERRORS[fault.kind](
            f"{fault.kind.replace('_', ' ')} in reply: {fault.data[:16].hex(' ')}"
        )


def _quote(data: bytes) -> str:
    """Foreign bytes for a message: text if printable (an NMEA sentence), else hex."""
    if not data:
        return "nothing"
    head = data[:_SAMPLE_BYTES]
    text = head.decode("ascii", "replace")
    if all(c.isprintable() or c in "\r\n" for c in text):
        return repr(text.strip())
    return head.hex(" ")
