"""The state packet: which groups it carries (the mask) and its payload codec.

Payload order (Ndirect ``Process_State_Pkg``), each group only if masked in:
IR nibbles (low nibble first, padded to a byte), one byte per sonar, bumper
(3 bytes, most significant first on the N150), x, y, steer, turret (s16),
translation, steering, turret velocities (s16), compass (s16); laser and
position attachments (not supported by odohil, CHOICE C14); then always the
motor-status byte, the timestamp (u32 ms) and the CPU and motor voltage bytes.
"""

from __future__ import annotations

from dataclasses import dataclass

from odohil.errors import ParameterError, UnexpectedReplyError
from odohil.protocol.nomad.numbers import (
    S16_MAX,
    U32_MAX,
    decode_s16,
    decode_u32,
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
        if len(self.sonar) != SONAR_COUNT or any(not 0 <= v <= 0xFF for v in self.sonar):
            raise ParameterError(f"16 sonar bytes needed, got {self.sonar}")
        if len(self.ir) != IR_COUNT or any(not 0 <= v <= 0xF for v in self.ir):
            raise ParameterError(f"16 IR nibbles needed, got {self.ir}")
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


def _require_supported(mask: StateMask, error: type[Exception]) -> None:
    if not mask.supported:
        raise error("odohil does not support laser or position attachments (CHOICE C14)")


def encode_state_payload(state: RobotState, mask: StateMask) -> bytes:
    """The state packet's payload for a mask."""
    _require_supported(mask, ParameterError)
    out = bytearray()
    nibbles = [v for v, on in zip(state.ir, mask.ir, strict=True) if on]
    for i in range(0, len(nibbles), 2):
        high = nibbles[i + 1] if i + 1 < len(nibbles) else 0
        out.append(nibbles[i] | high << 4)
    out += bytes(v for v, on in zip(state.sonar, mask.sonar, strict=True) if on)
    if mask.bumper:
        out += state.bumper.to_bytes(3, "big")
    pose = (state.x, state.y, state.steer, state.turret)
    vel = (state.trans_vel, state.steer_vel, state.turret_vel)
    for value, on in zip(pose + vel, mask.pose + mask.velocity, strict=True):
        if on:
            out += encode_s16(value)
    if mask.compass:
        out += encode_s16(state.compass)
    out.append(state.motor_status)
    out += encode_u32(state.timestamp_ms)
    out += bytes((state.voltage_cpu_raw, state.voltage_motor_raw))
    return bytes(out)


def decode_state_payload(payload: bytes, mask: StateMask) -> RobotState:
    """A state packet's payload; wrong size raises UnexpectedReplyError."""
    _require_supported(mask, UnexpectedReplyError)
    if len(payload) != mask.payload_size:
        raise UnexpectedReplyError(
            f"state payload of {len(payload)} bytes, the mask needs {mask.payload_size}"
        )
    pos = 0
    n_ir = sum(mask.ir)
    nibbles = [payload[i // 2] >> (4 * (i % 2)) & 0xF for i in range(n_ir)]
    pos += (n_ir + 1) // 2
    ir_values = iter(nibbles)
    ir = tuple(next(ir_values) if on else 0 for on in mask.ir)
    sonar_values = iter(payload[pos : pos + sum(mask.sonar)])
    pos += sum(mask.sonar)
    sonar = tuple(next(sonar_values) if on else 0 for on in mask.sonar)
    bumper = 0
    if mask.bumper:
        bumper = int.from_bytes(payload[pos : pos + 3], "big")
        pos += 3
    words: list[int] = []
    for on in (*mask.pose, *mask.velocity, mask.compass):
        if on:
            words.append(decode_s16(payload[pos : pos + 2]))
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
        timestamp_ms=decode_u32(payload[pos + 1 : pos + 5]),
        voltage_cpu_raw=payload[pos + 5],
        voltage_motor_raw=payload[pos + 6],
        ir=ir,
    )
