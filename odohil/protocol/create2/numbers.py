"""OI integers: 16 bits, high byte first, signed ones in two's complement.

Encoder counts (packets 43 and 44) are cumulative and roll over; a delta
between two readings is taken modulo 65536 and read as a signed 16-bit
number (CHOICE C2), which is right for both the spec's s16 reading and the
drivers' u16 reading of the same wire bytes, forwards and backwards through
the wrap, as long as a wheel turns less than 32767 counts (14.5 m) between
two readings.
"""

from __future__ import annotations

from odohil.errors import ParameterError

S16_MIN = -0x8000
S16_MAX = 0x7FFF
U16_MAX = 0xFFFF
U8_MAX = 0xFF
COUNTS_MODULUS = 0x10000
"""Encoder counts roll over at this many counts."""


def _check(value: int, low: int, high: int, what: str) -> None:
    if isinstance(value, bool) or not isinstance(value, int):
        raise ParameterError(f"{what} needs an int, got {value!r}")
    if not low <= value <= high:
        raise ParameterError(f"{what} out of range [{low}, {high}]: {value}")


def _need(data: bytes, size: int, what: str) -> None:
    if len(data) != size:
        raise ParameterError(f"{what} needs exactly {size} bytes, got {len(data)}")


def encode_u8(value: int) -> bytes:
    """One unsigned byte, 0..255."""
    _check(value, 0, U8_MAX, "u8")
    return bytes((value,))


def encode_s8(value: int) -> bytes:
    """One two's complement byte, -128..127."""
    _check(value, -0x80, 0x7F, "s8")
    return bytes((value & 0xFF,))


def encode_s16(value: int) -> bytes:
    """Two's complement 16 bits, high byte first; -32768..32767."""
    _check(value, S16_MIN, S16_MAX, "s16")
    return (value & U16_MAX).to_bytes(2, "big")


def encode_u16(value: int) -> bytes:
    """Unsigned 16 bits, high byte first; 0..65535."""
    _check(value, 0, U16_MAX, "u16")
    return value.to_bytes(2, "big")


def decode_u8(data: bytes) -> int:
    """One unsigned byte."""
    _need(data, 1, "u8")
    return data[0]


def decode_s8(data: bytes) -> int:
    """One two's complement byte."""
    _need(data, 1, "s8")
    return data[0] - 0x100 if data[0] & 0x80 else data[0]


def decode_u16(data: bytes) -> int:
    """Unsigned 16 bits, high byte first."""
    _need(data, 2, "u16")
    return int.from_bytes(data, "big")


def decode_s16(data: bytes) -> int:
    """Two's complement 16 bits, high byte first."""
    _need(data, 2, "s16")
    return int.from_bytes(data, "big", signed=True)


def to_signed16(value: int) -> int:
    """Any integer reduced modulo 65536 into [-32768, 32767]."""
    value &= U16_MAX
    return value - COUNTS_MODULUS if value > S16_MAX else value


def encoder_delta(previous: int, current: int) -> int:
    """Counts turned between two encoder readings (CHOICE C2).

    Both readings may be given as u16 (0..65535) or s16 (-32768..32767): the
    result is ``(current - previous) mod 65536`` mapped to [-32768, 32767],
    so 0x7FF0 -> 0x8010 is +32 and 0x0005 -> 0xFFF6 is -15.
    """
    return to_signed16(current - previous)
