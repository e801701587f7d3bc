"""Host requests as frozen dataclasses (wire units), and their codec.

Field ranges are checked on construction (ParameterError): s16 fields
|v| <= 32767, u16 fields 0..65535, byte fields 0..255.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import ClassVar

from odohil.errors import FramingError, OdohilError, ParameterError, UnexpectedReplyError
from odohil.protocol.nomad.codes import Code
from odohil.protocol.nomad.framing import Packet, encode_packet
from odohil.protocol.nomad.numbers import (
    decode_s16,
    decode_u16,
    encode_s16,
    encode_u8,
    encode_u16,
)

SONAR_COUNT = 16
ORDER_END = 255
"""Terminator of a ``conf_sn`` firing order."""


def _s16s(*values: int) -> bytes:
    return b"".join(encode_s16(v) for v in values)


def _u16s(*values: int) -> bytes:
    return b"".join(encode_u16(v) for v in values)


@dataclass(frozen=True)
class _Axes3S:
    """Three signed axis values: translation, steering, turret."""

    trans: int
    steer: int
    turret: int

    def __post_init__(self) -> None:
        _s16s(self.trans, self.steer, self.turret)

    def payload(self) -> bytes:
        return _s16s(self.trans, self.steer, self.turret)


@dataclass(frozen=True)
class _Axes3U:
    """Three unsigned axis values: translation, steering, turret."""

    trans: int
    steer: int
    turret: int

    def __post_init__(self) -> None:
        _u16s(self.trans, self.steer, self.turret)

    def payload(self) -> bytes:
        return _u16s(self.trans, self.steer, self.turret)


@dataclass(frozen=True)
class Ac(_Axes3U):
    """``ac``: accelerations for pr/pa/vm, 0.1 in/s^2 and 0.1 deg/s^2 (u16)."""

    code: ClassVar[Code] = Code.AC


@dataclass(frozen=True)
class Sp(_Axes3U):
    """``sp``: speeds for pr/pa, 0.1 in/s and 0.1 deg/s (u16); no motion."""

    code: ClassVar[Code] = Code.SP


@dataclass(frozen=True)
class Pr(_Axes3S):
    """``pr``: relative move, 0.1 in and 0.1 deg, all axes at once."""

    code: ClassVar[Code] = Code.PR


@dataclass(frozen=True)
class Pa(_Axes3S):
    """``pa``: absolute move, 0.1 in and 0.1 deg (N200 only in Ndirect)."""

    code: ClassVar[Code] = Code.PA


@dataclass(frozen=True)
class Vm(_Axes3S):
    """``vm``: velocity mode, 0.1 in/s and 0.1 deg/s, until the next command."""

    code: ClassVar[Code] = Code.VM


@dataclass(frozen=True)
class Ct:
    """``ct``: the 7 sensor-mask bytes (see ``state.StateMask.to_ct``)."""

    mask: bytes
    code: ClassVar[Code] = Code.CT

    def __post_init__(self) -> None:
        if len(self.mask) != 7:
            raise _param(f"ct needs 7 mask bytes, got {len(self.mask)}")

    def payload(self) -> bytes:
        return bytes(self.mask)


@dataclass(frozen=True)
class _Empty:
    def payload(self) -> bytes:
        return b""


@dataclass(frozen=True)
class Gs(_Empty):
    """``gs``: get the state packet."""

    code: ClassVar[Code] = Code.GS


@dataclass(frozen=True)
class St(_Empty):
    """``st``: stop and hold position."""

    code: ClassVar[Code] = Code.ST


@dataclass(frozen=True)
class Lp(_Empty):
    """``lp``: limp, motors unpowered."""

    code: ClassVar[Code] = Code.LP


@dataclass(frozen=True)
class Zr(_Empty):
    """``zr``: zero the robot; the reply comes when it has finished."""

    code: ClassVar[Code] = Code.ZR


@dataclass(frozen=True)
class GetSn(_Empty):
    """``get_sn``: sonar readings only."""

    code: ClassVar[Code] = Code.GET_SN


@dataclass(frozen=True)
class GetRc(_Empty):
    """``get_rc``: x, y, steer, turret only."""

    code: ClassVar[Code] = Code.GET_RC


@dataclass(frozen=True)
class GetRv(_Empty):
    """``get_rv``: the three velocities only."""

    code: ClassVar[Code] = Code.GET_RV


@dataclass(frozen=True)
class GetRa(_Empty):
    """``get_ra``: accelerations (the host ignores the payload; CHOICE C15)."""

    code: ClassVar[Code] = Code.GET_RA


@dataclass(frozen=True)
class GetBp(_Empty):
    """``get_bp``: bumper only."""

    code: ClassVar[Code] = Code.GET_BP


@dataclass(frozen=True)
class Tk:
    """``tk``: text to speak, sent NUL-terminated (ASCII, no NUL inside)."""

    text: str
    code: ClassVar[Code] = Code.TK

    def __post_init__(self) -> None:
        if "\0" in self.text or not self.text.isascii() or len(self.text) > 250:
            raise _param("tk text must be ASCII, without NUL, at most 250 characters")

    def payload(self) -> bytes:
        return self.text.encode("ascii") + b"\0"


@dataclass(frozen=True)
class Dp:
    """``dp``: define the current position, 0.1 in (s16)."""

    x: int
    y: int
    code: ClassVar[Code] = Code.DP

    def __post_init__(self) -> None:
        _s16s(self.x, self.y)

    def payload(self) -> bytes:
        return _s16s(self.x, self.y)


@dataclass(frozen=True)
class Da:
    """``da``: define the current steering and turret angles, 0.1 deg (s16)."""

    steer: int
    turret: int
    code: ClassVar[Code] = Code.DA

    def __post_init__(self) -> None:
        _s16s(self.steer, self.turret)

    def payload(self) -> bytes:
        return _s16s(self.steer, self.turret)


@dataclass(frozen=True)
class ConfSn:
    """``conf_sn``: firing rate (units of 4 ms) and firing order (sonar 0..15).

    On the wire the order always takes 16 bytes, ended by 255 when shorter.
    """

    rate: int
    order: tuple[int, ...] = field(default_factory=tuple)
    code: ClassVar[Code] = Code.CONF_SN

    def __post_init__(self) -> None:
        encode_u8(self.rate)
        if len(self.order) > SONAR_COUNT or any(
            isinstance(s, bool) or not isinstance(s, int) or not 0 <= s < SONAR_COUNT
            for s in self.order
        ):
            raise _param(f"conf_sn order needs at most 16 sonar numbers 0..15: {self.order}")

    def payload(self) -> bytes:
        tail = bytes([ORDER_END] * (SONAR_COUNT - len(self.order)))
        return bytes((self.rate, *self.order)) + tail


@dataclass(frozen=True)
class ConfTm:
    """``conf_tm``: watchdog timeout in whole seconds (0 turns it off)."""

    seconds: int
    code: ClassVar[Code] = Code.CONF_TM

    def __post_init__(self) -> None:
        encode_u8(self.seconds)

    def payload(self) -> bytes:
        return encode_u8(self.seconds)


@dataclass(frozen=True)
class Ws:
    """``ws``: wait until the chosen axes stop, or ``timeout_s`` seconds pass."""

    trans: bool
    steer: bool
    turret: bool
    timeout_s: int
    code: ClassVar[Code] = Code.WS

    def __post_init__(self) -> None:
        encode_u8(self.timeout_s)

    def payload(self) -> bytes:
        return bytes((int(self.trans), int(self.steer), int(self.turret), self.timeout_s))


@dataclass(frozen=True)
class ConfSer:
    """``conf_ser``: serial port number (byte) and baud (u16) on the robot side."""

    port: int
    baud: int
    code: ClassVar[Code] = Code.CONF_SER

    def __post_init__(self) -> None:
        encode_u8(self.port)
        encode_u16(self.baud)

    def payload(self) -> bytes:
        return encode_u8(self.port) + encode_u16(self.baud)


@dataclass(frozen=True)
class Mv:
    """``mv``: per-axis (mode u16, value s16); modes 0 ignore, 1 VM, 2 PR, 3 LP,
    4 AC, 5 SP, 6 PA, 7 TQ, 8 MT."""

    trans_mode: int
    trans: int
    steer_mode: int
    steer: int
    turret_mode: int
    turret: int
    code: ClassVar[Code] = Code.MV

    def __post_init__(self) -> None:
        self.payload()

    def payload(self) -> bytes:
        return b"".join(
            encode_u16(mode) + encode_s16(value)
            for mode, value in (
                (self.trans_mode, self.trans),
                (self.steer_mode, self.steer),
                (self.turret_mode, self.turret),
            )
        )


Request = (
    Ac
    | Sp
    | Pr
    | Pa
    | Vm
    | Ct
    | Gs
    | St
    | Lp
    | Tk
    | Dp
    | Zr
    | ConfSn
    | ConfTm
    | GetSn
    | GetRc
    | GetRv
    | GetRa
    | GetBp
    | Da
    | Ws
    | ConfSer
    | Mv
)


def _param(message: str) -> ParameterError:
    return ParameterError(message)


def encode_request(req: Request) -> bytes:
    """The request's whole packet on the wire."""
    return encode_packet(req.code, req.payload())


_FIXED_SIZE: dict[Code, int] = {
    Code.AC: 6,
    Code.SP: 6,
    Code.PR: 6,
    Code.PA: 6,
    Code.VM: 6,
    Code.CT: 7,
    Code.GS: 0,
    Code.ST: 0,
    Code.LP: 0,
    Code.ZR: 0,
    Code.GET_SN: 0,
    Code.GET_RC: 0,
    Code.GET_RV: 0,
    Code.GET_RA: 0,
    Code.GET_BP: 0,
    Code.DP: 4,
    Code.DA: 4,
    Code.CONF_SN: 17,
    Code.CONF_TM: 1,
    Code.WS: 4,
    Code.CONF_SER: 3,
    Code.MV: 12,
}

_EMPTY: dict[Code, type[Gs | St | Lp | Zr | GetSn | GetRc | GetRv | GetRa | GetBp]] = {
    Code.GS: Gs,
    Code.ST: St,
    Code.LP: Lp,
    Code.ZR: Zr,
    Code.GET_SN: GetSn,
    Code.GET_RC: GetRc,
    Code.GET_RV: GetRv,
    Code.GET_RA: GetRa,
    Code.GET_BP: GetBp,
}


def _words(payload: bytes, signed: bool) -> list[int]:
    decode = decode_s16 if signed else decode_u16
    return [decode(payload[i : i + 2]) for i in range(0, len(payload), 2)]


def decode_request(packet: Packet) -> Request:
    """The request a packet carries.

    Raises UnexpectedReplyError for a code odohil does not accept as a
    request (NAK, N200-only sensors, special, unknown) or content out of
    range, FramingError for a payload of the wrong size.
    """
    try:
        code = Code(packet.type)
    except ValueError:
        raise UnexpectedReplyError(f"unknown command code {packet.type}") from None
    p = packet.payload
    if code == Code.TK:
        if not p or p[-1] != 0:
            raise FramingError("tk text is not NUL-terminated")
        return _checked(lambda: Tk(p[:-1].decode("ascii")))
    size = _FIXED_SIZE.get(code)
    if size is None:
        raise UnexpectedReplyError(f"{code.name} ({code.value}) is not a request odohil accepts")
    if len(p) != size:
        raise FramingError(f"{code.name} needs {size} payload bytes, got {len(p)}")
    if code in _EMPTY:
        return _EMPTY[code]()
    return _checked(lambda: _decode_fixed(code, p))


def _decode_fixed(code: Code, p: bytes) -> Request:
    if code in (Code.AC, Code.SP):
        t, s, r = _words(p, signed=False)
        return Ac(t, s, r) if code == Code.AC else Sp(t, s, r)
    if code in (Code.PR, Code.PA, Code.VM):
        t, s, r = _words(p, signed=True)
        moves: dict[Code, type[Pr | Pa | Vm]] = {Code.PR: Pr, Code.PA: Pa, Code.VM: Vm}
        return moves[code](t, s, r)
    if code == Code.CT:
        return Ct(bytes(p))
    if code in (Code.DP, Code.DA):
        a, b = _words(p, signed=True)
        return Dp(a, b) if code == Code.DP else Da(a, b)
    if code == Code.CONF_SN:
        order = bytes(p[1:])
        end = order.find(ORDER_END)
        return ConfSn(p[0], tuple(order if end < 0 else order[:end]))
    if code == Code.CONF_TM:
        return ConfTm(p[0])
    if code == Code.WS:
        # The host clamps the flags to 0/1; any non-zero byte means "wait".
        return Ws(p[0] != 0, p[1] != 0, p[2] != 0, p[3])
    if code == Code.CONF_SER:
        return ConfSer(p[0], decode_u16(p[1:3]))
    modes = [decode_u16(p[i : i + 2]) for i in (0, 4, 8)]
    values = [decode_s16(p[i : i + 2]) for i in (2, 6, 10)]
    return Mv(modes[0], values[0], modes[1], values[1], modes[2], values[2])


def _checked(build: Callable[[], Request]) -> Request:
    try:
        return build()
    except (ValueError, OdohilError) as exc:
        if isinstance(exc, UnexpectedReplyError | FramingError):
            raise
        raise UnexpectedReplyError(f"request content out of range: {exc}") from exc
