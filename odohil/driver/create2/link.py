"""The Create 2's serial link: commands out, sensor readings in.

Readings are the packets the driver needs (:data:`SAMPLE_IDS`), taken either
by polling (Query List, replied raw: the input is flushed before each request
and requests come no faster than every 15 ms, facts §8) or from a stream
(frames every 15 ms, aligned on 19 and confirmed by their checksum, §6; only
where the frame fits the line's 15 ms, else polling). The
port is opened with ``serial.serial_for_url``, so a device, ``socket://``,
``rfc2217://`` and ``fakecreate2://`` share this code.
"""

from __future__ import annotations

import contextlib
import time
from dataclasses import dataclass
from typing import Literal

from odohil.driver.port import IO_ERRORS, Port, open_serial_url
from odohil.errors import (
    DisconnectedError,
    OdohilTimeoutError,
    ParameterError,
    ProtocolError,
)
from odohil.protocol.create2 import commands
from odohil.protocol.create2.opcodes import BAUD_RATES, DEFAULT_BAUD
from odohil.protocol.create2.packets import (
    CLIFF_PACKETS,
    Packet,
    decode_reply,
    reply_size,
)
from odohil.protocol.create2.stream import STREAM_PERIOD_S, StreamDecoder, frame_size

Sampling = Literal["poll", "stream"]
SAMPLINGS: tuple[Sampling, ...] = ("poll", "stream")
SAMPLE_IDS: tuple[int, ...] = (
    Packet.BUMPS_WHEEL_DROPS,
    *CLIFF_PACKETS,
    Packet.OI_MODE,
    Packet.LEFT_ENCODER_COUNTS,
    Packet.RIGHT_ENCODER_COUNTS,
)
"""Bumps and wheel drops, the four cliffs, the OI mode, both encoders: 10 data
bytes (a 21-byte stream frame, within the 28 bytes per 15 ms of 19200 baud)."""
READ_SLICE_S = 0.005
"""pyserial read timeout: how often the link checks its own deadlines, s."""
REPLY_TIMEOUT_S = 1.0
"""Longest wait for a reading, s (66 stream frames; the Nomad link's normal timeout)."""
DRAIN_QUIET_S = 0.05
"""The input is drained when nothing has come for this long, s (over three stream periods)."""
DRAIN_TIMEOUT_S = 1.0
"""Longest drain, s."""
_IO_ERRORS = IO_ERRORS


@dataclass(frozen=True)
class Reading:
    """One set of the driver's packets.

    Attributes:
        host_time_s: host monotonic time when it arrived, s.
        robot_time_s: the robot's clock: stream frames counted times 15 ms
            (frames come on the OI's own ticks however the host is scheduled);
            the host time when polling.
        bumps_drops: packet 7 (bit0 bump R, bit1 bump L, bit2 drop R, bit3 drop L).
        cliffs: packets 9-12 (left, front left, front right, right).
        mode_raw: packet 35 as sent (some robots add 1).
        left_counts, right_counts: packets 43 and 44 as s16.
    """

    host_time_s: float
    robot_time_s: float
    bumps_drops: int
    cliffs: tuple[int, int, int, int]
    mode_raw: int
    left_counts: int
    right_counts: int

    def hazards(self) -> list[str]:
        """What the sensors report that makes moving unsafe, in words."""
        found = []
        names = ("bump right", "bump left", "wheel drop right", "wheel drop left")
        found += [name for bit, name in enumerate(names) if self.bumps_drops & (1 << bit)]
        sides = ("left", "front left", "front right", "right")
        found += [f"cliff {side}" for side, value in zip(sides, self.cliffs, strict=True) if value]
        return found


def _reading(values: dict[int, int], host_time_s: float, robot_time_s: float) -> Reading:
    cliffs = tuple(values[p] for p in CLIFF_PACKETS)
    bumps = values[Packet.BUMPS_WHEEL_DROPS]
    if bumps > 0x1F or any(c > 1 for c in cliffs) or values[Packet.OI_MODE] > 4:
        raise ProtocolError(
            f"implausible reading (bumps {bumps}, cliffs {cliffs}, mode "
            f"{values[Packet.OI_MODE]}): the reply is out of step"
        )
    return Reading(
        host_time_s=host_time_s,
        robot_time_s=robot_time_s,
        bumps_drops=bumps,
        cliffs=(cliffs[0], cliffs[1], cliffs[2], cliffs[3]),
        mode_raw=values[Packet.OI_MODE],
        left_counts=values[Packet.LEFT_ENCODER_COUNTS],
        right_counts=values[Packet.RIGHT_ENCODER_COUNTS],
    )


def open_port(url: str, baud: int = DEFAULT_BAUD) -> Port:
    """Open ``url`` 8N1 without flow control (facts §2; CHOICE C1) at an OI rate."""
    if baud not in BAUD_RATES:
        raise ParameterError(f"baud must be one of {BAUD_RATES} for the Create 2, got {baud}")
    return open_serial_url(url, baud, READ_SLICE_S)


class Create2Link:
    """Commands and readings over one open port.

    Args:
        port: an open pyserial port.
        url: what it was opened from (for messages).
        baud: its line rate (for the line time of a reading).
        sampling: ``poll`` or ``stream`` (see the module docstring).
        reply_timeout_s: longest wait for a reading, s (``[serial] timeout_s``).
    """

    def __init__(
        self,
        port: Port,
        url: str,
        baud: int = DEFAULT_BAUD,
        sampling: Sampling = "poll",
        reply_timeout_s: float = REPLY_TIMEOUT_S,
    ) -> None:
        if sampling not in SAMPLINGS:
            raise ParameterError(f"sampling must be one of {SAMPLINGS}, got {sampling!r}")
        if sampling == "stream" and not stream_fits(baud):
            sampling = "poll"  # the frame would not fit the line: a corrupted stream
        self.port = port
        self.reply_timeout_s = reply_timeout_s
        self.url = url
        self.baud = baud
        self.sampling = sampling
        self.closed = False
        self.streaming = False
        self._decoder = StreamDecoder(SAMPLE_IDS)
        self._last_poll = -1.0
        self.readings = 0
        self.frames = 0
        """Stream frames received."""

    def send(self, data: bytes) -> None:
        """Write command bytes (DisconnectedError when the line is gone)."""
        if self.closed:
            raise DisconnectedError(f"{self.url} is closed")
        try:
            self.port.write(data)
        except _IO_ERRORS as exc:
            raise DisconnectedError(f"writing to {self.url}: {exc}") from exc

    @property
    def transfer_s(self) -> float:
        """Line time of one reading at the port's baud rate (10 bits a byte), s:
        the request and its reply when polling, one frame when streaming. By
        then the wheels have turned on."""
        if self.sampling == "poll":
            size = len(commands.query_list(SAMPLE_IDS)) + reply_size_of_samples()
        else:
            size = frame_size(SAMPLE_IDS)
        return size * 10.0 / self.baud

    def drain(self) -> None:
        """Wait until every byte written has left the host."""
        try:
            self.port.flush()
        except _IO_ERRORS as exc:
            raise DisconnectedError(f"flushing output to {self.url}: {exc}") from exc

    def _read(self, size: int) -> bytes:
        try:
            return bytes(self.port.read(size))
        except _IO_ERRORS as exc:
            raise DisconnectedError(f"reading from {self.url}: {exc}") from exc

    def flush_input(self) -> None:
        """Drop whatever arrived and was not read."""
        try:
            self.port.reset_input_buffer()
        except _IO_ERRORS as exc:
            raise DisconnectedError(f"flushing {self.url}: {exc}") from exc

    def ask(self, request: bytes, size: int, timeout_s: float | None = None) -> bytes:
        """Flush input, send a sensor request, read its ``size`` raw bytes.

        Raises OdohilTimeoutError when fewer arrive within ``timeout_s``
        (None: :attr:`reply_timeout_s`).
        """
        if timeout_s is None:
            timeout_s = self.reply_timeout_s
        wait = self._last_poll + STREAM_PERIOD_S - time.monotonic()
        if wait > 0:
            time.sleep(wait)
        self.flush_input()
        self.send(request)
        self._last_poll = time.monotonic()
        out = bytearray()
        deadline = self._last_poll + timeout_s
        while len(out) < size:
            if time.monotonic() >= deadline:
                raise OdohilTimeoutError(
                    f"{len(out)} of {size} reply bytes from {self.url} within {timeout_s:g} s "
                    f"(request {request.hex(' ')})"
                )
            out += self._read(size - len(out))
        return bytes(out)

    def start_stream(self) -> None:
        """Ask for a frame of :data:`SAMPLE_IDS` every 15 ms."""
        self._decoder.clear()
        self.send(commands.stream(SAMPLE_IDS))
        self.streaming = True

    def stop_stream(self) -> None:
        """Pause the stream (Pause/Resume ``150 0``, p.22; the list is kept)."""
        self.send(commands.pause_resume(False))
        self.streaming = False

    def drain_input(
        self, quiet_s: float = DRAIN_QUIET_S, timeout_s: float = DRAIN_TIMEOUT_S
    ) -> int:
        """Read and drop input until none has come for ``quiet_s``; the bytes
        dropped. ProtocolError when the robot is still sending after ``timeout_s``
        (a stream that did not pause)."""
        dropped = 0
        start = time.monotonic()
        quiet_since = start
        while True:
            got = self._read(4096)
            now = time.monotonic()
            if got:
                dropped += len(got)
                quiet_since = now
            elif now - quiet_since >= quiet_s:
                return dropped
            if now - start >= timeout_s:
                raise ProtocolError(
                    f"{self.url} still sends after {timeout_s:g} s ({dropped} bytes) "
                    "although its stream was paused"
                )

    def reading(self, timeout_s: float | None = None) -> Reading:
        """The freshest reading: polled, or the newest complete stream frame,
        within ``timeout_s`` (None: :attr:`reply_timeout_s`)."""
        if timeout_s is None:
            timeout_s = self.reply_timeout_s
        self.readings += 1
        if self.sampling == "poll" or not self.streaming:
            data = self.ask(commands.query_list(SAMPLE_IDS), reply_size_of_samples(), timeout_s)
            now = time.monotonic()
            return _reading(decode_reply(SAMPLE_IDS, data), now, now)
        deadline = time.monotonic() + timeout_s
        while True:
            try:
                waiting = self.port.in_waiting
            except _IO_ERRORS as exc:
                raise DisconnectedError(f"reading from {self.url}: {exc}") from exc
            frames = self._decoder.feed(self._read(max(1, waiting)))
            if frames:
                # only the newest frame: older ones are stale by 15 ms each
                self.frames += len(frames)
                robot_time = self.frames * STREAM_PERIOD_S
                return _reading(frames[-1].values, time.monotonic(), robot_time)
            if time.monotonic() >= deadline:
                raise OdohilTimeoutError(f"no stream frame from {self.url} in {timeout_s:g} s")

    def close(self) -> None:
        """Close the port. Idempotent."""
        if self.closed:
            return
        self.closed = True
        with contextlib.suppress(*_IO_ERRORS):
            self.port.close()


def stream_fits(baud: int) -> bool:
    """Whether the stream frame of :data:`SAMPLE_IDS` leaves the line within one
    15 ms period at ``baud`` (p.22: a stream beyond that becomes corrupted)."""
    return frame_size(SAMPLE_IDS) * 10.0 / baud <= STREAM_PERIOD_S


def reply_size_of_samples() -> int:
    """Raw bytes of a Query List reply of :data:`SAMPLE_IDS`."""
    return sum(reply_size(pid) for pid in SAMPLE_IDS)
