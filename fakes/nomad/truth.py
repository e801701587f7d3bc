"""The side channel a real robot does not have: the fake robot's TRUE pose.

The protocol never reveals it. For the pty emulator it is served on a
UNIX-domain socket: the client writes one line (its content is ignored; send
``truth``) and reads one JSON line, a :class:`TruthSnapshot`. The in-process
``fakerobot://`` port offers the same snapshot through ``Serial.truth()``.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from fakes.truth_channel import TruthChannelClient
from odohil.protocol.nomad import wire_units


@dataclass(frozen=True)
class MotionRecord:
    """One motion command the robot received and executed.

    Attributes:
        wall_s: wall seconds since the robot started.
        command: lower-case command name (``pr``, ``vm``, ``st``...).
        args: its arguments in wire units, in packet order.
    """

    wall_s: float
    command: str
    args: tuple[int, ...]


@dataclass(frozen=True)
class TruthSnapshot:
    """What the robot really did, at one instant.

    Attributes:
        sim_time_s: the robot's simulated clock, s.
        true_x_m, true_y_m: true position in the start frame, m.
        true_theta_rad: true heading (steering direction), rad, unwrapped.
        encoder_x, encoder_y: encoder position as reported, 0.1 in.
        encoder_steer, encoder_turret: encoder angles as reported, 0.1 deg (0..3599).
        moving: whether any axis moves (or is reported moving).
        motor_status: the motor-status byte as reported.
        motion_log: every motion command executed (pr pa vm mv zr st lp), in order.
        faults_fired: a line per fault injected, in order.
        disconnected: whether the serial line was cut (fault ``disconnect``).
    """

    sim_time_s: float
    true_x_m: float
    true_y_m: float
    true_theta_rad: float
    encoder_x: int
    encoder_y: int
    encoder_steer: int
    encoder_turret: int
    moving: bool
    motor_status: int
    motion_log: tuple[MotionRecord, ...]
    faults_fired: tuple[str, ...]
    disconnected: bool

    @property
    def encoder_x_m(self) -> float:
        """Encoder x, m."""
        return wire_units.wire_to_metres(self.encoder_x)

    @property
    def encoder_y_m(self) -> float:
        """Encoder y, m."""
        return wire_units.wire_to_metres(self.encoder_y)

    @property
    def encoder_steer_rad(self) -> float:
        """Encoder steering angle, rad (0..2 pi)."""
        return wire_units.wire_to_radians(self.encoder_steer)

    def to_json(self) -> str:
        """One JSON line (no newline)."""
        return json.dumps(asdict(self), separators=(",", ":"))

    @classmethod
    def from_json(cls, text: str) -> TruthSnapshot:
        """Parse :meth:`to_json` output."""
        raw: dict[str, Any] = json.loads(text)
        raw["motion_log"] = tuple(
            MotionRecord(float(r["wall_s"]), str(r["command"]), tuple(r["args"]))
            for r in raw["motion_log"]
        )
        raw["faults_fired"] = tuple(raw["faults_fired"])
        return cls(**raw)


class TruthClient(TruthChannelClient[TruthSnapshot]):
    """Client of the emulator's truth socket; use as a context manager.

    Args:
        path: the UNIX-domain socket path the emulator printed.
        timeout_s: how long one request may take, s.
    """

    def __init__(self, path: str | Path, timeout_s: float = 5.0) -> None:
        super().__init__(path, timeout_s, parse=TruthSnapshot.from_json, robot="fake robot")

    def snapshot(self) -> TruthSnapshot:
        """The robot's true pose and log, now."""
        return self.ask(b"truth\n")
