"""Sensor packets and groups (facts §5; OI specification pp.23-32).

A packet is an id with a fixed number of data bytes; a group id stands for
its member packets in order, replied back to back. Values are in OI units
(mm, mm/s, degrees, mA, counts). Packets 43 and 44 are the spec's s16; read
deltas between them with :func:`odohil.protocol.create2.numbers.encoder_delta`.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from enum import IntEnum

from odohil.errors import ParameterError, UnexpectedReplyError
from odohil.protocol.create2.numbers import (
    decode_s8,
    decode_s16,
    decode_u8,
    decode_u16,
    encode_s8,
    encode_s16,
    encode_u8,
    encode_u16,
)


class Packet(IntEnum):
    """The packet ids odohil reads by name."""

    BUMPS_WHEEL_DROPS = 7
    CLIFF_LEFT = 9
    CLIFF_FRONT_LEFT = 10
    CLIFF_FRONT_RIGHT = 11
    CLIFF_RIGHT = 12
    DISTANCE = 19
    ANGLE = 20
    OI_MODE = 35
    REQUESTED_VELOCITY = 39
    REQUESTED_RADIUS = 40
    REQUESTED_RIGHT_VELOCITY = 41
    REQUESTED_LEFT_VELOCITY = 42
    LEFT_ENCODER_COUNTS = 43
    RIGHT_ENCODER_COUNTS = 44
    STASIS = 58


BUMP_RIGHT = 0x01
BUMP_LEFT = 0x02
WHEEL_DROP_RIGHT = 0x04
WHEEL_DROP_LEFT = 0x08
"""Bits of packet 7."""

CLIFF_PACKETS = (
    Packet.CLIFF_LEFT,
    Packet.CLIFF_FRONT_LEFT,
    Packet.CLIFF_FRONT_RIGHT,
    Packet.CLIFF_RIGHT,
)


@dataclass(frozen=True)
class PacketSpec:
    """One single packet: its id, data bytes and integer type."""

    id: int
    size: int
    signed: bool

    def decode(self, data: bytes) -> int:
        """The value of the packet's data bytes."""
        if self.size == 1:
            return decode_s8(data) if self.signed else decode_u8(data)
        return decode_s16(data) if self.signed else decode_u16(data)

    def encode(self, value: int) -> bytes:
        """The data bytes of ``value``."""
        if self.size == 1:
            return encode_s8(value) if self.signed else encode_u8(value)
        return encode_s16(value) if self.signed else encode_u16(value)


def _table() -> dict[int, PacketSpec]:
    u8, u16, s8, s16 = (1, False), (2, False), (1, True), (2, True)
    kinds: dict[int, tuple[int, bool]] = dict.fromkeys(range(7, 19), u8)
    kinds.update({19: s16, 20: s16, 21: u8, 22: u16, 23: s16, 24: s8, 25: u16, 26: u16})
    kinds.update(dict.fromkeys(range(27, 32), u16))
    kinds.update({32: u8, 33: u16, 34: u8, 35: u8, 36: u8, 37: u8, 38: u8})
    kinds.update(dict.fromkeys(range(39, 45), s16))
    kinds[45] = u8
    kinds.update(dict.fromkeys(range(46, 52), u16))
    kinds.update({52: u8, 53: u8})
    kinds.update(dict.fromkeys(range(54, 58), s16))
    kinds[58] = u8
    return {pid: PacketSpec(pid, size, signed) for pid, (size, signed) in kinds.items()}


PACKETS: dict[int, PacketSpec] = _table()
"""Every single packet, 7..58."""

GROUPS: dict[int, tuple[int, ...]] = {
    0: tuple(range(7, 27)),
    1: tuple(range(7, 17)),
    2: tuple(range(17, 21)),
    3: tuple(range(21, 27)),
    4: tuple(range(27, 35)),
    5: tuple(range(35, 43)),
    6: tuple(range(7, 43)),
    100: tuple(range(7, 59)),
    101: tuple(range(43, 59)),
    106: tuple(range(46, 52)),
    107: tuple(range(54, 59)),
}
"""Member packets of every group id, in reply order (p.23)."""


def is_valid_id(packet_id: int) -> bool:
    """True for a single packet or a group id."""
    return packet_id in PACKETS or packet_id in GROUPS


def members(packet_id: int) -> tuple[int, ...]:
    """The single packets an id stands for (itself for a single packet)."""
    if packet_id in GROUPS:
        return GROUPS[packet_id]
    if packet_id in PACKETS:
        return (packet_id,)
    raise ParameterError(f"no sensor packet or group {packet_id}")


def reply_size(packet_id: int) -> int:
    """Data bytes of the reply to ``[142][packet_id]``."""
    return sum(PACKETS[m].size for m in members(packet_id))


def decode_reply(packet_ids: Iterable[int], data: bytes) -> dict[int, int]:
    """Values of the single packets in a Sensors or Query List reply.

    ``packet_ids`` are the ids asked for (groups allowed), in order; ``data``
    the raw reply (no header, no checksum). Raises UnexpectedReplyError when
    ``data`` is not exactly as long as the ids ask.
    """
    ids = list(packet_ids)
    expected = sum(reply_size(pid) for pid in ids)
    if len(data) != expected:
        raise UnexpectedReplyError(
            f"a reply to packets {ids} has {expected} bytes, got {len(data)}"
        )
    values: dict[int, int] = {}
    offset = 0
    for pid in ids:
        for member in members(pid):
            spec = PACKETS[member]
            values[member] = spec.decode(data[offset : offset + spec.size])
            offset += spec.size
    return values


def encode_reply(packet_ids: Iterable[int], values: Mapping[int, int]) -> bytes:
    """The raw reply to a Sensors or Query List request of ``packet_ids``
    (single packets missing from ``values`` read 0)."""
    out = bytearray()
    for pid in packet_ids:
        for member in members(pid):
            out += PACKETS[member].encode(values.get(member, 0))
    return bytes(out)
