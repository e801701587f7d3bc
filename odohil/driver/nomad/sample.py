"""One timestamped encoder reading, in SI units."""

from __future__ import annotations

from dataclasses import dataclass

from odohil.protocol.nomad.state import RobotState
from odohil.protocol.nomad.wire_units import wire_angle_in_turn, wire_to_metres, wire_to_radians

MOTOR_TRANS = 0b001
MOTOR_STEER = 0b010
MOTOR_TURRET = 0b100


@dataclass(frozen=True)
class EncoderSample:
    """What the encoders said at one moment.

    Attributes:
        host_time_s: host monotonic clock when the reply arrived, s.
        robot_time_s: the robot's timestamp, s.
        x_m, y_m: encoder position, m.
        steer_rad, turret_rad: encoder angles in [0, 2 pi), rad (CHOICE C6).
        trans_vel_m_s: m/s. steer_vel_rad_s, turret_vel_rad_s: rad/s.
        motor_status: bit0 translation, bit1 steering, bit2 turret active.
        x_wire, y_wire: position, 0.1 in. steer_wire, turret_wire: 0..3599, 0.1 deg.
    """

    host_time_s: float
    robot_time_s: float
    x_m: float
    y_m: float
    steer_rad: float
    turret_rad: float
    trans_vel_m_s: float
    steer_vel_rad_s: float
    turret_vel_rad_s: float
    motor_status: int
    x_wire: int
    y_wire: int
    steer_wire: int
    turret_wire: int

    @property
    def moving(self) -> bool:
        """Whether any axis is active."""
        return bool(self.motor_status & (MOTOR_TRANS | MOTOR_STEER | MOTOR_TURRET))

    def pose_text(self) -> str:
        """Short human-readable encoder pose, wire and SI."""
        return (
            f"x={self.x_wire} y={self.y_wire} (0.1 in) steer={self.steer_wire} "
            f"turret={self.turret_wire} (0.1 deg); x={self.x_m:.4f} m y={self.y_m:.4f} m"
        )

    @classmethod
    def from_state(cls, state: RobotState, host_time_s: float) -> EncoderSample:
        """Convert a state packet; angles reduced modulo 3600 wire units."""
        steer = wire_angle_in_turn(state.steer)
        turret = wire_angle_in_turn(state.turret)
        return cls(
            host_time_s=host_time_s,
            robot_time_s=state.timestamp_ms / 1000.0,
            x_m=wire_to_metres(state.x),
            y_m=wire_to_metres(state.y),
            steer_rad=wire_to_radians(steer),
            turret_rad=wire_to_radians(turret),
            trans_vel_m_s=wire_to_metres(state.trans_vel),
            steer_vel_rad_s=wire_to_radians(state.steer_vel),
            turret_vel_rad_s=wire_to_radians(state.turret_vel),
            motor_status=state.motor_status,
            x_wire=state.x,
            y_wire=state.y,
            steer_wire=steer,
            turret_wire=turret,
        )
