"""OI integers: 16 bits, high byte first, signed ones in two's complement.

Encoder counts (packets 43 and 44) are cumulative and roll over; a delta
between two readings is taken modulo 65536 and read as a signed 16-bit
number (CHOICE C2), which is right for both the spec's s16 reading and the
drivers' u16 reading of the same wire bytes, forwards and backwards through
the wrap, as long as a wheel turns less than 32767 counts (14.5 m) between
two readings.
"""

from __future__ import annotations

from odohil.protocol.numbers import (
    S16_MAX as S16_MAX,
)
from odohil.protocol.numbers import (
    U8_MAX as U8_MAX,
)
from odohil.protocol.numbers import (
    U16_MAX as U16_MAX,
)
from odohil.protocol.numbers import (
    decode_twos,
    decode_unsigned,
    encode_twos,
    encode_unsigned,
)

COUNTS_MODULUS = 0x10000
"""Encoder counts roll over at this many counts."""


def encode_u8(value: int) -> bytes:
    """One unsigned byte, 0..255."""
    return encode_unsigned(value, 1, "big", "u8")


def encode_s8(value: int) -> bytes:
    """One two's complement byte, -128..127."""
    return encode_twos(value, 1, "big", "s8")


def encode_s16(value: int) -> bytes:
    """Two's complement 16 bits, high byte first; -32768..32767."""
    return encode_twos(value, 2, "big", "s16")


def encode_u16(value: int) -> bytes:
    """Unsigned 16 bits, high byte first; 0..65535."""
    return encode_unsigned(value, 2, "big", "u16")


def decode_u8(data: bytes) -> int:
    """One unsigned byte."""
    return decode_unsigned(data, 1, "big", "u8")


def decode_s8(data: bytes) -> int:
    """One two's complement byte."""
    return decode_twos(data, 1, "big", "s8")


def decode_u16(data: bytes) -> int:
    """Unsigned 16 bits, high byte first."""
    return decode_unsigned(data, 2, "big", "u16")


def decode_s16(data: bytes) -> int:
    """Two's complement 16 bits, high byte first."""
    return decode_twos(data, 2, "big", "s16")


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
