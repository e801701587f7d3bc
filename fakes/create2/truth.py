"""The fake Create 2's side channel: its TRUE pose, and test hooks.

Served like the fake Nomad's (fakes/nomad/truth.py): a UNIX-domain stream
socket; the client writes one line and reads one JSON line, a
:class:`Create2Truth`. A line ``event NAME`` first injects the safety event
NAME (fakes/create2/config.py ``EVENTS``); any other line only asks.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from fakes.truth_channel import TruthChannelClient


@dataclass(frozen=True)
class CommandRecord:
    """One command the robot executed (sensor requests are not logged).

    Attributes:
        wall_s: wall seconds since the robot started.
        opcode: the OI opcode.
        data: its data bytes.
        mode: the OI mode after it (0 Off .. 3 Full).
    """

    wall_s: float
    opcode: int
    data: tuple[int, ...]
    mode: int


@dataclass(frozen=True)
class Create2Truth:
    """What the robot really did, at one instant.

    Attributes:
        sim_time_s: the robot's simulated clock, s.
        true_x_m, true_y_m: true position in the start frame, m.
        true_theta_rad: true heading, rad, unwrapped.
        left_counts, right_counts: the encoders' cumulative counts (not wrapped).
        mode: the OI mode (0 Off, 1 Passive, 2 Safe, 3 Full), as it really is.
        asleep: after Power (133) until the ``wake`` hook.
        moving: whether a wheel turns.
        right_mm_s, left_mm_s: the wheels' commanded speeds, mm/s.
        travel_m: encoder distance driven since power-on, m.
        commands: every non-sensor command executed, in order.
        faults_fired: a line per fault or event injected, in order.
        disconnected: whether the line was cut (fault ``disconnect``).
        unknown_opcodes: command bytes the OI skipped as undefined opcodes.
        framing_errors: bytes from the host the OI dropped (a host at another
            line rate, or bytes within 100 ms of a Baud command).
        dropped_out_bytes: bytes the robot could not send (its send buffer
            full: a stream beyond the line rate).
        baud: the robot's line rate now, baud.
        motion_lost_s: wall seconds the motion has been held because the host
            was behind in reading (the pty fake's bound,
            fakes/create2/clock.py ``ReadBoundClock``), s.
        wall_s: wall seconds since the robot started: the clock of
            ``CommandRecord.wall_s`` (``sim_time_s`` is the motion's clock,
            scaled and held while the host is behind), s.
    """

    sim_time_s: float
    true_x_m: float
    true_y_m: float
    true_theta_rad: float
    left_counts: int
    right_counts: int
    mode: int
    asleep: bool
    moving: bool
    right_mm_s: float
    left_mm_s: float
    travel_m: float
    commands: tuple[CommandRecord, ...]
    faults_fired: tuple[str, ...]
    disconnected: bool
    unknown_opcodes: int = 0
    framing_errors: int = 0
    dropped_out_bytes: int = 0
    baud: int = 115200
    motion_lost_s: float = 0.0
    wall_s: float = 0.0

    def to_json(self) -> str:
        """One JSON line (no newline)."""
        return json.dumps(asdict(self), separators=(",", ":"))

    @classmethod
    def from_json(cls, text: str) -> Create2Truth:
        """Parse :meth:`to_json` output."""
        raw: dict[str, Any] = json.loads(text)
        raw["commands"] = tuple(
            CommandRecord(float(r["wall_s"]), int(r["opcode"]), tuple(r["data"]), int(r["mode"]))
            for r in raw["commands"]
        )
        raw["faults_fired"] = tuple(raw["faults_fired"])
        return cls(**raw)

    def true_pose(self) -> tuple[float, float, float]:
        """(x m, y m, theta rad)."""
        return (self.true_x_m, self.true_y_m, self.true_theta_rad)


class Create2TruthClient(TruthChannelClient[Create2Truth]):
    """Client of the fake Create 2's truth socket; a context manager.

    Args:
        path: the UNIX-domain socket path the fake printed.
        timeout_s: how long one request may take, s.
    """

    def __init__(self, path: str | Path, timeout_s: float = 5.0) -> None:
        super().__init__(path, timeout_s, parse=Create2Truth.from_json, robot="fake Create 2")

    def snapshot(self) -> Create2Truth:
        """The robot's true state now."""
        return self.ask(b"truth\n")

    def event(self, name: str) -> Create2Truth:
        """Inject a safety event (config ``EVENTS``); the state after it."""
        return self.ask(f"event {name}\n".encode())

    def true_pose(self) -> tuple[float, float, float]:
        """(x m, y m, theta rad) now (the session's TruthReader protocol)."""
        return self.snapshot().true_pose()
