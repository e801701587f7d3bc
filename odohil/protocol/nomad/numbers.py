"""Wire integers: 16 and 32 bits, low byte first, signed ones in sign-magnitude.

Nomad's host library encodes a signed value as its magnitude with the sign in
the top bit (``-100`` is ``64 80``), not in two's complement. Decoding the
bit pattern "minus zero" (``00 80``) gives 0, as the host library does.
"""

from __future__ import annotations

from odohil.protocol.numbers import (
    S16_MAX as S16_MAX,
)
from odohil.protocol.numbers import (
    S32_MAX as S32_MAX,
)
from odohil.protocol.numbers import (
    U8_MAX as U8_MAX,
)
from odohil.protocol.numbers import (
    U16_MAX as U16_MAX,
)
from odohil.protocol.numbers import (
    U32_MAX as U32_MAX,
)
from odohil.protocol.numbers import (
    check_range,
    check_size,
    decode_unsigned,
    encode_unsigned,
)


def encode_u8(value: int) -> bytes:
    """One unsigned byte, 0..255."""
    return encode_unsigned(value, 1, "little", "u8")


def encode_s16(value: int) -> bytes:
    """Sign-magnitude 16 bits, low byte first; |value| <= 32767."""
    check_range(value, -S16_MAX, S16_MAX, "s16")
    magnitude = abs(value)
    high = (magnitude >> 8) | (0x80 if value < 0 else 0)
    return bytes((magnitude & 0xFF, high))


def decode_s16(data: bytes) -> int:
    """Inverse of :func:`encode_s16` (exactly 2 bytes)."""
    check_size(data, 2, "s16")
    magnitude = data[0] | ((data[1] & 0x7F) << 8)
    return -magnitude if data[1] & 0x80 else magnitude


def encode_u16(value: int) -> bytes:
    """Unsigned 16 bits, low byte first; 0..65535."""
    return encode_unsigned(value, 2, "little", "u16")


def decode_u16(data: bytes) -> int:
    """Inverse of :func:`encode_u16` (exactly 2 bytes)."""
    return decode_unsigned(data, 2, "little", "u16")


def encode_s32(value: int) -> bytes:
    """Sign-magnitude 32 bits (sign on bit 31), low byte first."""
    check_range(value, -S32_MAX, S32_MAX, "s32")
    raw = abs(value) | (0x8000_0000 if value < 0 else 0)
    return raw.to_bytes(4, "little")


def decode_s32(data: bytes) -> int:
    """Inverse of :func:`encode_s32` (exactly 4 bytes)."""
    check_size(data, 4, "s32")
    raw = int.from_bytes(data, "little")
    magnitude = raw & S32_MAX
    return -magnitude if raw & 0x8000_0000 else magnitude


def encode_u32(value: int) -> bytes:
    """Unsigned 32 bits, low byte first."""
    return encode_unsigned(value, 4, "little", "u32")


def decode_u32(data: bytes) -> int:
    """Inverse of :func:`encode_u32` (exactly 4 bytes)."""
    return decode_unsigned(data, 4, "little", "u32")
