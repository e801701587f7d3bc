"""Wire integers: 16 and 32 bits, low byte first, signed ones in sign-magnitude.

Nomad's host library encodes a signed value as its magnitude with the sign in
the top bit (``-100`` is ``64 80``), not in two's complement. Decoding the
bit pattern "minus zero" (``00 80``) gives 0, as the host library does.
"""

from __future__ import annotations

from odohil.errors import ParameterError

S16_MAX = 0x7FFF
U16_MAX = 0xFFFF
S32_MAX = 0x7FFF_FFFF
U32_MAX = 0xFFFF_FFFF
U8_MAX = 0xFF


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


def encode_s16(value: int) -> bytes:
    """Sign-magnitude 16 bits, low byte first; |value| <= 32767."""
    _check(value, -S16_MAX, S16_MAX, "s16")
    magnitude = abs(value)
    high = (magnitude >> 8) | (0x80 if value < 0 else 0)
    return bytes((magnitude & 0xFF, high))


def decode_s16(data: bytes) -> int:
    """Inverse of :func:`encode_s16` (exactly 2 bytes)."""
    _need(data, 2, "s16")
    magnitude = data[0] | ((data[1] & 0x7F) << 8)
    return -magnitude if data[1] & 0x80 else magnitude


def encode_u16(value: int) -> bytes:
    """Unsigned 16 bits, low byte first; 0..65535."""
    _check(value, 0, U16_MAX, "u16")
    return value.to_bytes(2, "little")


def decode_u16(data: bytes) -> int:
    """Inverse of :func:`encode_u16` (exactly 2 bytes)."""
    _need(data, 2, "u16")
    return int.from_bytes(data, "little")


def encode_s32(value: int) -> bytes:
    """Sign-magnitude 32 bits (sign on bit 31), low byte first."""
    _check(value, -S32_MAX, S32_MAX, "s32")
    raw = abs(value) | (0x8000_0000 if value < 0 else 0)
    return raw.to_bytes(4, "little")


def decode_s32(data: bytes) -> int:
    """Inverse of :func:`encode_s32` (exactly 4 bytes)."""
    _need(data, 4, "s32")
    raw = int.from_bytes(data, "little")
    magnitude = raw & S32_MAX
    return -magnitude if raw & 0x8000_0000 else magnitude


def encode_u32(value: int) -> bytes:
    """Unsigned 32 bits, low byte first."""
    _check(value, 0, U32_MAX, "u32")
    return value.to_bytes(4, "little")


def decode_u32(data: bytes) -> int:
    """Inverse of :func:`encode_u32` (exactly 4 bytes)."""
    _need(data, 4, "u32")
    return int.from_bytes(data, "little")
