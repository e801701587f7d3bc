"""An independent byte-level OI host for the fake's tests.

Written from the facts document (§4-§6, §11) with struct and plain
arithmetic: it imports nothing from odohil, so the fake is checked against
the document rather than against odohil's own codec.
"""

from __future__ import annotations

import struct
import time

import serial

START, SAFE, FULL, STOP, RESET, BAUD = 128, 131, 132, 173, 7, 129
SENSORS, QUERY, STREAM, PAUSE = 142, 149, 148, 150
DRIVE, DIRECT = 137, 145
DEFINED_OPCODES = frozenset({7, *range(128, 147), 148, 149, 150, 162, 163, 164, 165, 167, 168, 173})
"""Every opcode the spec defines (p.8-22; 147 and 151-158 were removed, p.40)."""
BAUD_CODES = (300, 600, 1200, 2400, 4800, 9600, 14400, 19200, 28800, 38400, 57600, 115200)
"""Baud command (129) codes 0-11 (p.9)."""
LIBCREATE_IDS = (
    7,
    8,
    9,
    10,
    11,
    12,
    13,
    14,
    15,
    17,
    18,
    21,
    22,
    23,
    24,
    25,
    26,
    35,
    43,
    44,
    45,
    46,
    47,
    48,
    49,
    50,
    51,
    52,
    53,
    58,
)
"""The 30 packets libcreate streams from a Create 2 (facts §6): a 75-byte frame."""


def direct(right: int, left: int) -> bytes:
    """Drive Direct: right wheel first, s16 big-endian."""
    return struct.pack(">Bhh", DIRECT, right, left)


def drive(velocity: int, radius: int) -> bytes:
    """Drive: velocity and radius, s16 big-endian."""
    return struct.pack(">Bhh", DRIVE, velocity, radius)


def split_frames(data: bytes) -> list[bytes]:
    """Every well-formed stream frame in ``data`` (19, N, N bytes, checksum: sum 0)."""
    frames, i = [], 0
    while i + 2 < len(data):
        if data[i] == 19:
            n = data[i + 1]
            frame = data[i : i + n + 3]
            if len(frame) == n + 3 and sum(frame) % 256 == 0:
                frames.append(frame)
                i += n + 3
                continue
        i += 1
    return frames


class Host:
    """Raw bytes over a pyserial port to the fake's pty."""

    def __init__(self, device: str, baud: int = 115200) -> None:
        self.port = serial.Serial(device, baud, timeout=0.05)

    def set_baud(self, baud: int) -> None:
        """Change the host's line rate (pyserial sets the tty's speed)."""
        self.port.baudrate = baud

    def close(self) -> None:
        """Close the port."""
        self.port.close()

    def send(self, data: bytes) -> None:
        """Write raw bytes."""
        self.port.write(data)

    def read_for(self, seconds: float) -> bytes:
        """Every byte that arrives within ``seconds``."""
        out = bytearray()
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline:
            out += self.port.read(4096)
        return bytes(out)

    def ask(self, request: bytes, size: int, timeout_s: float = 1.0) -> bytes:
        """Flush input, send ``request``, read exactly ``size`` bytes (or fewer on timeout)."""
        self.port.reset_input_buffer()
        self.port.write(request)
        out = bytearray()
        deadline = time.monotonic() + timeout_s
        while len(out) < size and time.monotonic() < deadline:
            out += self.port.read(size - len(out))
        return bytes(out)

    def mode(self) -> int | None:
        """Packet 35, or None when nothing answers (OI Off)."""
        reply = self.ask(bytes((SENSORS, 35)), 1, 0.2)
        return reply[0] if reply else None

    def encoders(self) -> tuple[int, int]:
        """Packets 43, 44 as unsigned 16-bit counts (left, right)."""
        reply = self.ask(bytes((QUERY, 2, 43, 44)), 4)
        left, right = struct.unpack(">HH", reply)
        return left, right

    def stasis(self) -> int:
        """Packet 58: bit0 forward progress, bit1 stasis disabled (p.32)."""
        return self.ask(bytes((SENSORS, 58)), 1)[0]

    def requested(self) -> tuple[int, int]:
        """Packets 41, 42: right and left velocity last requested, mm/s."""
        right, left = struct.unpack(">hh", self.ask(bytes((QUERY, 2, 41, 42)), 4))
        return right, left


def delta(previous: int, current: int) -> int:
    """((current - previous) mod 65536) read as s16 (facts C2)."""
    d = (current - previous) % 65536
    return d - 65536 if d >= 32768 else d
