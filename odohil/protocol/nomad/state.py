"""The state packet: which groups it carries (the mask) and its payload codec.

Payload order (Ndirect ``Process_State_Pkg``), each group only if masked in:
IR nibbles (low nibble first, padded to a byte), one byte per sonar, bumper
(3 bytes, most significant first on the N150), x, y, steer, turret (s16),
translation, steering, turret velocities (s16), compass (s16); laser and
position attachments (not supported by odohil, CHOICE C14); then always the
motor-status byte, the timestamp (u32 ms) and the CPU and motor voltage bytes.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

from odohil.errors import ParameterError, UnexpectedReplyError
from odohil.protocol.nomad.numbers import (
    S16_MAX,
    U32_MAX,
    encode_s16,
    encode_u32,
)

IR_COUNT = 16
SONAR_COUNT = 16
BUMPER_MAX = 0xFF_FFFF
TAIL_BYTES = 1 + 4 + 2
"""Motor status, timestamp, two voltage bytes: present in every state packet."""

_ALL = (True,) * 16
_NONE = (False,) * 16
_NO_IR = (0,) * IR_COUNT


def _bits(byte: int) -> tuple[bool, ...]:
    return tuple(bool(byte >> i & 1) for i in range(8))


def _byte(bits: tuple[bool, ...]) -> int:
    return sum(1 << i for i, bit in enumerate(bits) if bit)


@dataclass(frozen=True)
class StateMask:
    """Which groups a state packet carries (Ndirect ``usedSmask``).

    Attributes:
        ir: 16 flags, infrared sensors 0..15.
        sonar: 16 flags, sonars 0..15.
        bumper: the 3 bumper bytes.
        pose: 4 flags: x, y, steer, turret.
        velocity: 3 flags: translation, steering, turret velocity.
        compass: the compass s16.
        laser: the laser block (N200 only; not supported).
        attachments: position-attachment bits (1 IR, 2 sonar, 4 bumper,
            8 laser, 16 compass; not supported).
    """

    ir: tuple[bool, ...] = _NONE
    sonar: tuple[bool, ...] = _ALL
    bumper: bool = True
    pose: tuple[bool, bool, bool, bool] = (True, True, True, True)
    velocity: tuple[bool, bool, bool] = (True, True, True)
    compass: bool = True
    laser: bool = False
    attachments: int = 0

    def __post_init__(self) -> None:
        if len(self.ir) != IR_COUNT or len(self.sonar) != SONAR_COUNT:
            raise ParameterError("a mask has 16 IR and 16 sonar flags")
        if len(self.pose) != 4 or len(self.velocity) != 3:
            raise ParameterError("a mask has 4 pose and 3 velocity flags")
        if not 0 <= self.attachments <= 0x1F:
            raise ParameterError(f"attachment bits are 0..31, got {self.attachments}")

    @property
    def supported(self) -> bool:
        """Whether odohil can encode and decode packets for this mask."""
        return not self.laser and self.attachments == 0

    @property
    def payload_size(self) -> int:
        """State payload bytes for this mask (laser and attachments excluded)."""
        n_ir = sum(self.ir)
        return (
            (n_ir + 1) // 2
            + sum(self.sonar)
            + (3 if self.bumper else 0)
            + 2 * (sum(self.pose) + sum(self.velocity) + int(self.compass))
            + TAIL_BYTES
        )

    @classmethod
    def from_ct(cls, mask_bytes: bytes) -> StateMask:
        """The mask a ``ct`` packet sets (2.7 packing).

        Bytes 0-1: IR 0..15; 2-3: sonar 0..15; 4: bumper, x, y, steer, turret,
        trans, steer, turret velocity (bit 0 first); 5 bit 0: laser; 6 bit 0:
        compass, bits 1-5: attachments (IR, sonar, bumper, laser, compass).
        """
        if len(mask_bytes) != 7:
            raise ParameterError(f"ct carries 7 mask bytes, got {len(mask_bytes)}")
        b = mask_bytes
        group = _bits(b[4])
        return cls(
            ir=_bits(b[0]) + _bits(b[1]),
            sonar=_bits(b[2]) + _bits(b[3]),
            bumper=group[0],
            pose=(group[1], group[2], group[3], group[4]),
            velocity=(group[5], group[6], group[7]),
            compass=bool(b[6] & 1),
            laser=bool(b[5] & 1),
            attachments=(b[6] >> 1) & 0x1F,
        )

    def to_ct(self) -> bytes:
        """The 7 ``ct`` mask bytes for this mask (inverse of :meth:`from_ct`)."""
        group = (self.bumper, *self.pose, *self.velocity)
        return bytes(
            (
                _byte(self.ir[:8]),
                _byte(self.ir[8:]),
                _byte(self.sonar[:8]),
                _byte(self.sonar[8:]),
                _byte(group),
                int(self.laser),
                int(self.compass) | self.attachments << 1,
            )
        )


N150_MASK = StateMask()
"""The 2.7 default for a non-N200 model: 16 sonars, bumper, pose, velocities,
compass; no IR, laser or attachments. 42 payload bytes, 48 on the wire."""


@dataclass(frozen=True)
class RobotState:
    """One state packet, in wire units; groups not in the mask read as 0.

    Attributes:
        sonar: 16 ranges, inches (0..255).
        bumper: 24 bumper bits.
        x, y: position, 0.1 in. steer, turret: angles, 0.1 deg.
        trans_vel: 0.1 in/s. steer_vel, turret_vel: 0.1 deg/s.
        compass: compass reading (s16).
        motor_status: bit0 translation, bit1 steering, bit2 turret active.
        timestamp_ms: robot clock, ms (u32).
        voltage_cpu_raw, voltage_motor_raw: raw voltage bytes.
        ir: 16 infrared readings (0..15).
    """

    sonar: tuple[int, ...] = (0,) * SONAR_COUNT
    bumper: int = 0
    x: int = 0
    y: int = 0
    steer: int = 0
    turret: int = 0
    trans_vel: int = 0
    steer_vel: int = 0
    turret_vel: int = 0
    compass: int = 0
    motor_status: int = 0
    timestamp_ms: int = 0
    voltage_cpu_raw: int = 0
    voltage_motor_raw: int = 0
    ir: tuple[int, ...] = (0,) * IR_COUNT

    def __post_init__(self) -> None:
        sonar, ir = self.sonar, self.ir
        if len(sonar) != SONAR_COUNT or min(sonar) < 0 or max(sonar) > 0xFF:
            raise ParameterError(f"16 sonar bytes needed, got {self.sonar}")
        if len(ir) != IR_COUNT or min(ir) < 0 or max(ir) > 0xF:
            raise ParameterError(f"16 IR nibbles needed, got {self.ir}")
        words = (self.x, self.y, self.steer, self.turret, self.trans_vel, self.steer_vel)
        if max(map(abs, words)) > S16_MAX or abs(self.turret_vel) > S16_MAX:
            for name in ("x", "y", "steer", "turret", "trans_vel", "steer_vel", "turret_vel"):
                if abs(getattr(self, name)) > S16_MAX:
                    raise ParameterError(f"{name} out of s16 range: {getattr(self, name)}")
        if abs(self.compass) > S16_MAX:
            raise ParameterError(f"compass out of s16 range: {self.compass}")
        if not 0 <= self.bumper <= BUMPER_MAX:
            raise ParameterError(f"bumper is 24 bits, got {self.bumper}")
        if not 0 <= self.timestamp_ms <= U32_MAX:
            raise ParameterError(f"timestamp is u32, got {self.timestamp_ms}")
        for name in ("motor_status", "voltage_cpu_raw", "voltage_motor_raw"):
            if not 0 <= getattr(self, name) <= 0xFF:
                raise ParameterError(f"{name} is one byte, got {getattr(self, name)}")

    @property
    def moving(self) -> bool:
        """Whether any axis is active (motor-status bits 0-2)."""
        return bool(self.motor_status & 0b111)


@dataclass(frozen=True)
class _Layout:
    """What a mask puts in a payload, worked out once per mask."""

    supported: bool
    size: int
    n_ir: int
    n_sonar: int
    all_sonar: bool
    bumper: bool
    words: tuple[bool, ...]
    """x, y, steer, turret, the three velocities, compass."""


@functools.cache
def _layout(mask: StateMask) -> _Layout:
    return _Layout(
        supported=mask.supported,
        size=mask.payload_size,
        n_ir=sum(mask.ir),
        n_sonar=sum(mask.sonar),
        all_sonar=all(mask.sonar),
        bumper=mask.bumper,
        words=(*mask.pose, *mask.velocity, mask.compass),
    )


def _require_supported(mask: StateMask, error: type[Exception]) -> None:
    if not _layout(mask).supported:
        raise error("odohil does not support laser or position attachments (CHOICE C14)")


def encode_state_payload(state: RobotState, mask: StateMask) -> bytes:
    """The state packet's payload for a mask."""
    _require_supported(mask, ParameterError)
    layout = _layout(mask)
    out = bytearray()
    if layout.n_ir:
        nibbles = [v for v, on in zip(state.ir, mask.ir, strict=True) if on]
        for i in range(0, len(nibbles), 2):
            high = nibbles[i + 1] if i + 1 < len(nibbles) else 0
            out.append(nibbles[i] | high << 4)
    if layout.all_sonar:
        out += bytes(state.sonar)
    else:
        out += bytes(v for v, on in zip(state.sonar, mask.sonar, strict=True) if on)
    if layout.bumper:
        out += state.bumper.to_bytes(3, "big")
    values = (
        state.x,
        state.y,
        state.steer,
        state.turret,
        state.trans_vel,
        state.steer_vel,
        state.turret_vel,
        state.compass,
    )
    for value, on in zip(values, layout.words, strict=True):
        if not on:
            continue
        if type(value) is int and -S16_MAX <= value <= S16_MAX:  # encode_s16, inline
            magnitude = -value if value < 0 else value
            out.append(magnitude & 0xFF)
            out.append(magnitude >> 8 | (0x80 if value < 0 else 0))
        else:
            out += encode_s16(value)  # raises as it does
    out.append(state.motor_status)
    out += encode_u32(state.timestamp_ms)
    out += bytes((state.voltage_cpu_raw, state.voltage_motor_raw))
    return bytes(out)


def _check_payload(payload: bytes, mask: StateMask) -> _Layout:
    _require_supported(mask, UnexpectedReplyError)
    layout = _layout(mask)
    if len(payload) != layout.size:
        raise UnexpectedReplyError(
            f"state payload of {len(payload)} bytes, the mask needs {layout.size}"
        )
    return layout


def decode_state_payload(payload: bytes, mask: StateMask) -> RobotState:
    """A state packet's payload; wrong size raises UnexpectedReplyError."""
    layout = _check_payload(payload, mask)
    pos = 0
    if layout.n_ir:
        n_ir = layout.n_ir
        nibbles = [payload[i // 2] >> (4 * (i % 2)) & 0xF for i in range(n_ir)]
        pos += (n_ir + 1) // 2
        ir_values = iter(nibbles)
        ir = tuple(next(ir_values) if on else 0 for on in mask.ir)
    else:
        ir = _NO_IR
    n_sonar = layout.n_sonar
    if layout.all_sonar:
        sonar = tuple(payload[pos : pos + n_sonar])
    else:
        sonar_values = iter(payload[pos : pos + n_sonar])
        sonar = tuple(next(sonar_values) if on else 0 for on in mask.sonar)
    pos += n_sonar
    bumper = 0
    if layout.bumper:
        bumper = int.from_bytes(payload[pos : pos + 3], "big")
        pos += 3
    words: list[int] = []
    for on in layout.words:
        if on:  # decode_s16, inline
            low, high = payload[pos], payload[pos + 1]
            magnitude = low | (high & 0x7F) << 8
            words.append(-magnitude if high & 0x80 else magnitude)
            pos += 2
        else:
            words.append(0)
    return RobotState(
        sonar=sonar,
        bumper=bumper,
        x=words[0],
        y=words[1],
        steer=words[2],
        turret=words[3],
        trans_vel=words[4],
        steer_vel=words[5],
        turret_vel=words[6],
        compass=words[7],
        motor_status=payload[pos],
        timestamp_ms=int.from_bytes(payload[pos + 1 : pos + 5], "little"),
        voltage_cpu_raw=payload[pos + 5],
        voltage_motor_raw=payload[pos + 6],
        ir=ir,
    )


def state_timestamp_ms(payload: bytes, mask: StateMask) -> int:
    """The robot timestamp (ms) of a state packet's payload, the rest not
    decoded; raises as :func:`decode_state_payload` does (a payload of the
    right size always decodes)."""
    layout = _check_payload(payload, mask)
    return int.from_bytes(payload[layout.size - 6 : layout.size - 2], "little")
