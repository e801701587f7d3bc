"""Fixed-width wire integers shared by every robot protocol.

Range and size checks, and unsigned and two's complement integers of 1, 2 or
4 bytes in either byte order. Each robot subpackage picks its byte order and
keeps its own signed encodings (sign-magnitude on the Nomad) and ranges.
"""

from __future__ import annotations

from typing import Literal

from odohil.errors import ParameterError

ByteOrder = Literal["big", "little"]

U8_MAX = 0xFF
U16_MAX = 0xFFFF
U32_MAX = 0xFFFF_FFFF
S16_MAX = 0x7FFF
S32_MAX = 0x7FFF_FFFF


def check_range(value: int, low: int, high: int, what: str) -> None:
    """Raise ParameterError unless ``value`` is an int (not a bool) in [low, high]."""
    if isinstance(value, bool) or not isinstance(value, int):
        raise ParameterError(f"{what} needs an int, got {value!r}")
    if not low <= value <= high:
        raise ParameterError(f"{what} out of range [{low}, {high}]: {value}")


def check_size(data: bytes, size: int, what: str) -> None:
    """Raise ParameterError unless ``data`` is exactly ``size`` bytes."""
    if len(data) != size:
        raise ParameterError(f"{what} needs exactly {size} bytes, got {len(data)}")


def encode_unsigned(value: int, size: int, order: ByteOrder, what: str) -> bytes:
    """Unsigned ``size``-byte integer, 0..2**(8*size)-1."""
    check_range(value, 0, (1 << (8 * size)) - 1, what)
    return value.to_bytes(size, order)


def decode_unsigned(data: bytes, size: int, order: ByteOrder, what: str) -> int:
    """Inverse of :func:`encode_unsigned` (exactly ``size`` bytes)."""
    check_size(data, size, what)
    return int.from_bytes(data, order)


def encode_twos(value: int, size: int, order: ByteOrder, what: str) -> bytes:
    """Two's complement ``size``-byte integer, -2**(8*size-1)..2**(8*size-1)-1."""
    half = 1 << (8 * size - 1)
    check_range(value, -half, half - 1, what)
    return value.to_bytes(size, order, signed=True)


def decode_twos(data: bytes, size: int, order: ByteOrder, what: str) -> int:
    """Inverse of :func:`encode_twos` (exactly ``size`` bytes)."""
    check_size(data, size, what)
    return int.from_bytes(data, order, signed=True)
