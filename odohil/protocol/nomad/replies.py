"""Robot replies: state packets (reply type = request code, CHOICE C2), the
single-group replies of ``get_rc``/``get_rv``/``get_sn``/``get_bp``/``get_ra``,
and NAK."""

from __future__ import annotations

from dataclasses import dataclass

from odohil.errors import NakError, ParameterError, UnexpectedReplyError
from odohil.protocol.nomad.codes import STATE_REPLY_CODES, Code
from odohil.protocol.nomad.framing import Packet, encode_packet
from odohil.protocol.nomad.messages import Request
from odohil.protocol.nomad.numbers import (
    decode_s16,
    decode_u16,
    decode_u32,
    encode_s16,
    encode_u16,
    encode_u32,
)
from odohil.protocol.nomad.state import (
    BUMPER_MAX,
    SONAR_COUNT,
    RobotState,
    StateMask,
    decode_state_payload,
    encode_state_payload,
)

NAK_BYTES = encode_packet(Code.NAK, b"")
"""The NAK reply, ``01 02 00 08 0B 5C``."""


@dataclass(frozen=True)
class RcReply:
    """``get_rc`` reply: x, y (0.1 in), steer, turret (0.1 deg), s16 each."""

    x: int
    y: int
    steer: int
    turret: int

    def __post_init__(self) -> None:
        for value in (self.x, self.y, self.steer, self.turret):
            encode_s16(value)


@dataclass(frozen=True)
class RvReply:
    """``get_rv`` reply: translation (0.1 in/s), steering and turret (0.1 deg/s)."""

    trans: int
    steer: int
    turret: int

    def __post_init__(self) -> None:
        for value in (self.trans, self.steer, self.turret):
            encode_s16(value)


@dataclass(frozen=True)
class RaReply:
    """``get_ra`` reply (CHOICE C15: the host ignores its payload; odohil
    uses the three ``ac`` settings as u16)."""

    trans: int
    steer: int
    turret: int

    def __post_init__(self) -> None:
        for value in (self.trans, self.steer, self.turret):
            encode_u16(value)


@dataclass(frozen=True)
class SnReply:
    """``get_sn`` reply: 16 sonar bytes (inches) and the timestamp (ms)."""

    sonar: tuple[int, ...]
    timestamp_ms: int

    def __post_init__(self) -> None:
        if len(self.sonar) != SONAR_COUNT or any(not 0 <= v <= 0xFF for v in self.sonar):
            raise ParameterError(f"16 sonar bytes needed, got {self.sonar}")
        encode_u32(self.timestamp_ms)


@dataclass(frozen=True)
class BpReply:
    """``get_bp`` reply: 24 bumper bits and the timestamp (ms)."""

    bumper: int
    timestamp_ms: int

    def __post_init__(self) -> None:
        if not 0 <= self.bumper <= BUMPER_MAX:
            raise ParameterError(f"bumper is 24 bits, got {self.bumper}")
        encode_u32(self.timestamp_ms)


Reply = RobotState | RcReply | RvReply | RaReply | SnReply | BpReply


def encode_state_reply(code: int, state: RobotState, mask: StateMask) -> bytes:
    """A state packet answering request ``code`` (reply type = request code)."""
    return encode_packet(code, encode_state_payload(state, mask))


def encode_rc_reply(reply: RcReply) -> bytes:
    """The ``get_rc`` reply packet."""
    payload = b"".join(encode_s16(v) for v in (reply.x, reply.y, reply.steer, reply.turret))
    return encode_packet(Code.GET_RC, payload)


def encode_rv_reply(reply: RvReply) -> bytes:
    """The ``get_rv`` reply packet."""
    payload = b"".join(encode_s16(v) for v in (reply.trans, reply.steer, reply.turret))
    return encode_packet(Code.GET_RV, payload)


def encode_ra_reply(reply: RaReply) -> bytes:
    """The ``get_ra`` reply packet."""
    payload = b"".join(encode_u16(v) for v in (reply.trans, reply.steer, reply.turret))
    return encode_packet(Code.GET_RA, payload)


def encode_sn_reply(reply: SnReply) -> bytes:
    """The ``get_sn`` reply packet (no position attachments)."""
    return encode_packet(Code.GET_SN, bytes(reply.sonar) + encode_u32(reply.timestamp_ms))


def encode_bp_reply(reply: BpReply) -> bytes:
    """The ``get_bp`` reply packet (bumper most significant byte first, N150)."""
    payload = reply.bumper.to_bytes(3, "big") + encode_u32(reply.timestamp_ms)
    return encode_packet(Code.GET_BP, payload)


def _size(payload: bytes, size: int, code: Code) -> None:
    if len(payload) != size:
        raise UnexpectedReplyError(
            f"{code.name} reply of {len(payload)} payload bytes, expected {size}"
        )


def decode_reply(packet: Packet, request: Request | Code, mask: StateMask) -> Reply:
    """The reply to ``request``; NakError on NAK, UnexpectedReplyError on a
    type that does not answer the request or a payload of the wrong size."""
    code = request if isinstance(request, Code) else request.code
    if packet.type == Code.NAK:
        raise NakError(f"robot answered NAK to {code.name}")
    if packet.type != code:
        raise UnexpectedReplyError(f"reply type {packet.type} does not answer {code.name}")
    p = packet.payload
    if code in STATE_REPLY_CODES:
        return decode_state_payload(p, mask)
    if code == Code.GET_RC:
        _size(p, 8, code)
        x, y, steer, turret = (decode_s16(p[i : i + 2]) for i in range(0, 8, 2))
        return RcReply(x, y, steer, turret)
    if code == Code.GET_RV:
        _size(p, 6, code)
        return RvReply(*(decode_s16(p[i : i + 2]) for i in range(0, 6, 2)))
    if code == Code.GET_RA:
        _size(p, 6, code)
        return RaReply(*(decode_u16(p[i : i + 2]) for i in range(0, 6, 2)))
    if code == Code.GET_SN:
        _size(p, SONAR_COUNT + 4, code)
        return SnReply(tuple(p[:SONAR_COUNT]), decode_u32(p[SONAR_COUNT:]))
    if code == Code.GET_BP:
        _size(p, 7, code)
        return BpReply(int.from_bytes(p[:3], "big"), decode_u32(p[3:]))
    raise UnexpectedReplyError(f"odohil does not decode replies to {code.name}")
