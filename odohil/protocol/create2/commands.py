"""Host commands as bytes, and a splitter of a command byte stream (facts §4).

Commands have no framing, checksum or acknowledgement: an opcode and a fixed
(or, for lists, announced) number of data bytes. 16-bit fields are two's
complement, high byte first.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from odohil.errors import ParameterError
from odohil.protocol.create2.numbers import encode_s16
from odohil.protocol.create2.opcodes import BAUD_RATES, Opcode, data_bytes
from odohil.protocol.create2.packets import is_valid_id

MAX_SPEED_MM_S = 500
"""Largest wheel or drive speed, mm/s (p.13-14)."""
MAX_RADIUS_MM = 2000
"""Largest drive radius, mm (p.13)."""
MAX_PWM = 255
STRAIGHT = 0x7FFF
"""Drive radius meaning straight (0x8000 means the same)."""
SPIN_CW = -1
SPIN_CCW = 1

RESYNC_STARTS = 1 + Opcode.START + 1
"""Start bytes in :data:`RESYNC` (130): a list command (Stream, Query List)
cut right after its opcode reads the first Start as its count (128) and the
next 128 as packet ids (invalid, so no bytes); one Start more then acts. Any
other command the host may have left pending (at most 15 data bytes: every
one but Song) is completed by the first Starts."""
RESYNC = bytes((Opcode.START,)) * RESYNC_STARTS
"""What the host sends to resynchronise the OI's command parser (facts §9, S6:
send Start "enough times"; C10 in protocols/create2/README.md, which says why
not C10's 16 zero bytes and a Start): a command cut short waits for its data
bytes (p.8), so the first Starts complete it and the rest are Starts, which
leave the OI in Passive with the wheels stopped. Only defined opcodes, unlike
zero bytes (opcode 0 is not in the specification). A Drive left pending
completes with 0x8080 fields for the one byte time (87 us at 115200 baud)
before the next Start stops it. 130 bytes: 11 ms at 115200 baud."""


def _speed(value: int, what: str) -> bytes:
    if isinstance(value, bool) or not isinstance(value, int):
        raise ParameterError(f"{what} needs an int in mm/s, got {value!r}")
    if not -MAX_SPEED_MM_S <= value <= MAX_SPEED_MM_S:
        raise ParameterError(
            f"{what} out of range [-{MAX_SPEED_MM_S}, {MAX_SPEED_MM_S}] mm/s: {value}"
        )
    return encode_s16(value)


def start() -> bytes:
    """Start: Off -> Passive."""
    return bytes((Opcode.START,))


def safe() -> bytes:
    """Safe mode."""
    return bytes((Opcode.SAFE,))


def full() -> bytes:
    """Full mode: no safety stops (only when the robot description asks)."""
    return bytes((Opcode.FULL,))


def stop_oi() -> bytes:
    """Stop: the OI goes Off and streams stop."""
    return bytes((Opcode.STOP,))


def reset() -> bytes:
    """Reset: Off, as if the battery were reinserted; prints a banner."""
    return bytes((Opcode.RESET,))


def baud(rate: int) -> bytes:
    """Baud: switch the line to ``rate`` (one of :data:`BAUD_RATES`)."""
    if rate not in BAUD_RATES:
        raise ParameterError(f"baud must be one of {BAUD_RATES}, got {rate!r}")
    return bytes((Opcode.BAUD, BAUD_RATES.index(rate)))


def drive(velocity_mm_s: int, radius_mm: int) -> bytes:
    """Drive: ``velocity_mm_s`` along a radius; :data:`STRAIGHT`, 0x8000 (as
    -32768), :data:`SPIN_CW` and :data:`SPIN_CCW` are the special radii."""
    specials = (STRAIGHT, -0x8000, SPIN_CW, SPIN_CCW)
    if radius_mm not in specials and not -MAX_RADIUS_MM <= radius_mm <= MAX_RADIUS_MM:
        raise ParameterError(
            f"radius out of range [-{MAX_RADIUS_MM}, {MAX_RADIUS_MM}] mm "
            f"(or a special value): {radius_mm}"
        )
    return bytes((Opcode.DRIVE,)) + _speed(velocity_mm_s, "velocity") + encode_s16(radius_mm)


def drive_direct(right_mm_s: int, left_mm_s: int) -> bytes:
    """Drive Direct: each wheel's speed, mm/s, RIGHT wheel first."""
    return (
        bytes((Opcode.DRIVE_DIRECT,))
        + _speed(right_mm_s, "right wheel speed")
        + _speed(left_mm_s, "left wheel speed")
    )


def drive_pwm(right: int, left: int) -> bytes:
    """Drive PWM: each wheel's duty, -255..255, right first."""
    for value, what in ((right, "right PWM"), (left, "left PWM")):
        if not -MAX_PWM <= value <= MAX_PWM:
            raise ParameterError(f"{what} out of range [-{MAX_PWM}, {MAX_PWM}]: {value}")
    return bytes((Opcode.DRIVE_PWM,)) + encode_s16(right) + encode_s16(left)


def _ids(packet_ids: Sequence[int]) -> bytes:
    for pid in packet_ids:
        if not is_valid_id(pid):
            raise ParameterError(f"no sensor packet or group {pid}")
    if len(packet_ids) > 255:
        raise ParameterError(f"at most 255 packet ids, got {len(packet_ids)}")
    return bytes((len(packet_ids), *packet_ids))


def sensors(packet_id: int) -> bytes:
    """Sensors: one packet or group, replied raw."""
    if not is_valid_id(packet_id):
        raise ParameterError(f"no sensor packet or group {packet_id}")
    return bytes((Opcode.SENSORS, packet_id))


def query_list(packet_ids: Sequence[int]) -> bytes:
    """Query List: several packets, replied back to back, raw."""
    return bytes((Opcode.QUERY_LIST,)) + _ids(packet_ids)


def stream(packet_ids: Sequence[int]) -> bytes:
    """Stream: a frame of these packets every 15 ms (no ids: stop streaming)."""
    return bytes((Opcode.STREAM,)) + _ids(packet_ids)


def pause_resume(resume: bool) -> bytes:
    """Pause (False) or resume (True) the stream, keeping its list."""
    return bytes((Opcode.PAUSE_RESUME, 1 if resume else 0))


@dataclass(frozen=True)
class Command:
    """One command as received: its opcode and data bytes (unknown opcodes
    come out with ``known=False`` and no data)."""

    opcode: int
    data: bytes
    known: bool = True


class CommandSplitter:
    """Splits the bytes a host sends into :class:`Command` values.

    A command whose data bytes have not all arrived waits for them, forever
    (p.8); an opcode the OI does not have is passed on as unknown, one byte.
    """

    def __init__(self) -> None:
        self._buf = bytearray()

    @property
    def pending(self) -> bytes:
        """Bytes of a command still waiting for its data."""
        return bytes(self._buf)

    def feed(self, data: bytes) -> list[Command]:
        """Add received bytes; return every complete command, in order."""
        self._buf += data
        out: list[Command] = []
        while self._buf:
            opcode = self._buf[0]
            need = data_bytes(opcode, bytes(self._buf[1:]))
            if need is None:
                break
            if need < 0:
                out.append(Command(opcode, b"", known=False))
                del self._buf[:1]
                continue
            if len(self._buf) < 1 + need:
                break
            out.append(Command(opcode, bytes(self._buf[1 : 1 + need])))
            del self._buf[: 1 + need]
        return out
