"""The fake Create 2: OI bytes in, bytes out, a body that moves in between.

Transport-free like the fake Nomad's engine (fakes/nomad/engine.py), with the
same interface, so the same pty server and pyserial port can carry it:
:meth:`Create2Engine.receive` takes what the host wrote, and
:meth:`Create2Engine.take_output` hands out the bytes (or the
:class:`~fakes.nomad.engine.Disconnect` marker) that are due.

Behaviour follows the facts document's §3-§9 and CHOICEs C1-C17 (see
protocols/create2/README.md): the mode state machine, replies sent at once
from sensor values that change on 15 ms ticks, stream frames on those
ticks, safety stops in Safe, faults fired at set encoder distances.

Where the specification says more than "it answers" (protocols/create2/README.md,
C25-C29): packet 58 reads 1 only while driving straight forward; the robot's
line has a rate (``config.baud``, changed by the Baud command) and the host's
(:attr:`Create2Engine.host_baud`, which the transport reports) must match it or
each side reads garbage (fakes/create2/line.py); what the robot sends goes
through a bounded send buffer drained at its line rate, so a stream beyond the
rate is cut short (corrupted), never queued without bound; Passive sleeps after
5 minutes (simulated) without a command; Safe and Full take effect
``config.mode_change_s`` after their command.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable

from fakes.create2.body import Create2Body
from fakes.create2.clock import ReadBoundClock
from fakes.create2.config import DRAG_FACTOR, EVENTS, Create2Config
from fakes.create2.line import accepted, carried
from fakes.create2.truth import CommandRecord, Create2Truth
from fakes.nomad.engine import DISCONNECT, Disconnect
from odohil.errors import ParameterError
from odohil.protocol.create2.commands import (
    MAX_PWM,
    MAX_RADIUS_MM,
    MAX_SPEED_MM_S,
    Command,
    CommandSplitter,
)
from odohil.protocol.create2.numbers import decode_s16
from odohil.protocol.create2.opcodes import BAUD_RATES, Mode, Opcode
from odohil.protocol.create2.packets import (
    BUMP_LEFT,
    BUMP_RIGHT,
    WHEEL_DROP_LEFT,
    WHEEL_DROP_RIGHT,
    Packet,
    encode_reply,
    is_valid_id,
    members,
)
from odohil.protocol.create2.stream import STREAM_PERIOD_S, encode_frame, frame_size
from odohil.science.simulator import make_rng

_LOG = logging.getLogger(__name__)

Output = bytes | Disconnect

HALF_BASE_MM = 117.5
"""Half the wheel base in the Drive radius formula (C16)."""
ANGLE_BUG_FACTOR = 0.324056
"""Packet 20 on firmware <= 3.4.0 reads degrees times this (C11)."""
BATTERY = {21: 0, 22: 16028, 23: -111, 24: 21, 25: 1888, 26: 2068}
"""Battery packets of a real Create 2 (C17)."""
CLIFF_IDS = {
    "cliff_left": Packet.CLIFF_LEFT,
    "cliff_front_left": Packet.CLIFF_FRONT_LEFT,
    "cliff_front_right": Packet.CLIFF_FRONT_RIGHT,
    "cliff_right": Packet.CLIFF_RIGHT,
}
TX_BUFFER_BYTES = 128
"""The robot's send buffer, bytes (C26): bytes that would not fit behind what is
still waiting to leave at the line rate are dropped."""
BAUD_SWITCH_S = 0.1
"""After a Baud command the robot drops what arrives for this long, s (p.9:
"wait 100 ms before sending commands at the new baud rate")."""
SENSOR_OPCODES = frozenset({Opcode.SENSORS, Opcode.QUERY_LIST})
ACTUATORS = frozenset(
    {
        Opcode.DRIVE,
        Opcode.DRIVE_DIRECT,
        Opcode.DRIVE_PWM,
        Opcode.MOTORS,
        Opcode.MOTORS_PWM,
        Opcode.LEDS,
        Opcode.SONG,
        Opcode.PLAY,
        Opcode.SCHEDULING_LEDS,
        Opcode.DIGIT_LEDS_RAW,
        Opcode.DIGIT_LEDS_ASCII,
    }
)


def drive_wheels(velocity: int, radius: int) -> tuple[float, float]:
    """Right and left wheel speeds (mm/s) of Drive ``velocity``, ``radius`` (C16, C30).

    The special radii drive straight (0x8000, 0x7FFF) or spin (-1, +1); radius 0,
    which the specification leaves undefined, drives straight too (C30); any
    other radius is clamped to +-2000 mm and turns about that radius, the wheel
    speeds scaled down together (the radius kept) so the faster wheel is at
    most 500 mm/s. Defined for every pair of s16 values.
    """
    v = max(-MAX_SPEED_MM_S, min(MAX_SPEED_MM_S, velocity))
    if radius in (0x7FFF, -0x8000, 0):
        return float(v), float(v)
    if radius == -1:
        return float(-v), float(v)
    if radius == 1:
        return float(v), float(-v)
    r = max(-MAX_RADIUS_MM, min(MAX_RADIUS_MM, radius))
    right, left = v * (r + HALF_BASE_MM) / r, v * (r - HALF_BASE_MM) / r
    if abs(right) > MAX_SPEED_MM_S or abs(left) > MAX_SPEED_MM_S:
        ratio = (r - HALF_BASE_MM) / (r + HALF_BASE_MM)  # left / right
        if abs(ratio) <= 1.0:
            right = math.copysign(MAX_SPEED_MM_S, right)
            left = right * ratio
        else:
            left = math.copysign(MAX_SPEED_MM_S, left)
            right = left / ratio
    return right, left


class Create2Engine:
    """One fake Create 2 (see the module docstring).

    Args:
        config: its settings.
        clock: wall clock in seconds (monotonic); injectable for tests.
        host_bound_s: when set (wall s, positive), the motion runs at most this
            long past the newest instant up to which the host has read all the
            fake wrote (the transport reports it: :meth:`host_read`;
            fakes/create2/clock.py :class:`ReadBoundClock`), so a starved host
            finds its wheels at most this far past its last reading, never a
            leg driven on. Stream ticks, mode changes and Passive's sleep stay
            on the wall clock. None: the motion follows the wall clock.
    """

    def __init__(
        self,
        config: Create2Config,
        clock: Callable[[], float] = time.monotonic,
        host_bound_s: float | None = None,
    ) -> None:
        if host_bound_s is not None and not host_bound_s > 0.0:
            raise ParameterError(f"host_bound_s must be positive, got {host_bound_s!r}")
        self.config = config
        self.clock = clock
        self.wall0 = clock()
        self._motion = None if host_bound_s is None else ReadBoundClock(host_bound_s, self.wall0)
        self.body = Create2Body(
            config.errors,
            config.geometry,
            make_rng(config.seed),
            config.segment_m,
            config.encoder_origin,
        )
        self.mode = Mode.OFF
        self.asleep = False
        self.baud = config.baud
        self.host_baud: int | None = None
        """The host's line rate as the transport knows it (None: the same as the robot's)."""
        self._baud_switch_until = -1.0
        self._tx_free_at = -1.0
        self._pending_mode: tuple[Mode, float] | None = None
        self._last_command_wall = self.wall0
        self.unknown_opcodes = 0
        self.framing_errors = 0
        self.dropped_out_bytes = 0
        self._splitter = CommandSplitter()
        self._out: list[tuple[float, Output]] = []
        self._tick = 0
        self.values: dict[int, int] = {}
        self.bumps_drops = 0
        self.cliffs: set[int] = set()
        self.requested = {39: 0, 40: 0, 41: 0, 42: 0}
        self.stream_ids: tuple[int, ...] = ()
        self.stream_paused = False
        self._pending_faults = list(config.faults)
        self.faults_fired: list[str] = []
        self.commands: list[CommandRecord] = []
        self.muted = False
        self.garble_next = False
        self.disconnected = False
        self._update_values()

    # ---- clocks ---------------------------------------------------------------
    def sim_time(self, wall: float) -> float:
        """Simulated (motion) seconds at wall time ``wall``: held while the host
        is more than ``host_bound_s`` behind in reading (class docstring)."""
        if self._motion is None:
            return (wall - self.wall0) * self.config.time_scale
        return self._motion(wall) * self.config.time_scale

    def host_read(self, seen: float, now: float | None = None) -> None:
        """At wall time ``now`` the host has read everything the fake wrote up
        to wall time ``seen`` (s; ``now`` when nothing is left unread): the
        motion may run until ``seen + host_bound_s``. Nothing without a bound."""
        if self._motion is None:
            return
        if now is None:
            now = self.clock()
        self.poll(now)  # the ticks up to now, on the clock as it was
        self._motion.host_read(seen, now)

    def motion_lost_s(self, now: float | None = None) -> float:
        """Wall seconds the motion has been held so far (0 without a bound)."""
        if self._motion is None:
            return 0.0
        return self._motion.lost_s(self.clock() if now is None else now)

    def _tick_wall(self, index: int) -> float:
        return self.wall0 + index * STREAM_PERIOD_S

    # ---- transport interface ----------------------------------------------------
    def receive(self, data: bytes) -> None:
        """Bytes written by the host, in any chunking; executed at once."""
        now = self.clock()
        self.poll(now)
        if self.disconnected or not data or self.asleep:
            return
        if now < self._baud_switch_until:
            self.framing_errors += len(data)
            return
        if self.host_baud is not None and self.host_baud != self.baud:
            data, errors = accepted(data, self.host_baud, self.baud)
            self.framing_errors += errors
        self.body.advance(self.sim_time(now))
        for command in self._splitter.feed(data):
            if now < self._baud_switch_until:  # sent at the old rate after a Baud
                self.framing_errors += 1 + len(command.data)
                continue
            self._execute(command, now)

    def poll(self, now: float | None = None) -> None:
        """Let wall time pass up to ``now``: 15 ms ticks, frames, faults."""
        if now is None:
            now = self.clock()
        while self._tick_wall(self._tick + 1) <= now:
            self._tick += 1
            at = self._tick_wall(self._tick)
            self.body.advance(self.sim_time(at))
            self._fire_faults(at)
            self._settle_mode(at)
            self._maybe_sleep(at)
            self._update_values()
            if self._streaming():
                self._emit(at, encode_frame(self.stream_ids, self._read_values(self.stream_ids)))
        self._settle_mode(now)

    def _streaming(self) -> bool:
        return (
            bool(self.stream_ids)
            and not self.stream_paused
            and self.mode != Mode.OFF
            and not self.asleep
        )

    def _settle_mode(self, now: float) -> None:
        """A Safe or Full command takes effect ``config.mode_change_s`` after it (C28)."""
        if self._pending_mode is not None and now >= self._pending_mode[1]:
            self.mode = self._pending_mode[0]
            self._pending_mode = None
            self._update_values_now()

    def _maybe_sleep(self, now: float) -> None:
        """Passive sleeps after ``config.passive_sleep_s`` simulated seconds
        without a command (p.7; C27)."""
        limit = self.config.passive_sleep_s
        if limit is None or self.mode != Mode.PASSIVE or self.asleep:
            return
        if (now - self._last_command_wall) * self.config.time_scale >= limit:
            _LOG.info("Passive for %g s without a command: asleep", limit)
            self._enter_passive()
            self.asleep = True

    def take_output(self, now: float | None = None) -> list[Output]:
        """The writes due by ``now``, in order (bytes, or the disconnect marker)."""
        if now is None:
            now = self.clock()
        self.poll(now)
        due: list[Output] = []
        while self._out and self._out[0][0] <= now:
            item = self._out.pop(0)[1]
            due.append(item)
            if isinstance(item, Disconnect):
                self._out.clear()
        return due

    def next_output_wall(self) -> float | None:
        """Wall time of the next write: queued output or the next stream frame."""
        if self._out:
            return self._out[0][0]
        if self._streaming() and not self.muted:
            return self._tick_wall(self._tick + 1)
        return None

    def truth(self, now: float | None = None) -> Create2Truth:
        """The true state and logs (the side channel; never on the wire)."""
        if now is None:
            now = self.clock()
        self.poll(now)
        x, y, theta = self.body.true_pose()
        return Create2Truth(
            sim_time_s=self.body.t,
            true_x_m=x,
            true_y_m=y,
            true_theta_rad=theta,
            left_counts=self.body.left.counts,
            right_counts=self.body.right.counts,
            mode=int(self.mode),
            asleep=self.asleep,
            moving=self.body.moving,
            right_mm_s=self.body.right.speed_mm_s,
            left_mm_s=self.body.left.speed_mm_s,
            travel_m=self.body.travel_m,
            commands=tuple(self.commands),
            faults_fired=tuple(self.faults_fired),
            disconnected=self.disconnected,
            unknown_opcodes=self.unknown_opcodes,
            framing_errors=self.framing_errors,
            dropped_out_bytes=self.dropped_out_bytes,
            baud=self.baud,
            motion_lost_s=self.motion_lost_s(now),
            wall_s=now - self.wall0,
        )

    def event(self, name: str) -> None:
        """A test hook: inject a safety event now (config ``EVENTS``)."""
        if name not in EVENTS:
            raise ParameterError(f"unknown event {name!r}; one of {', '.join(EVENTS)}")
        now = self.clock()
        self.poll(now)
        self.body.advance(self.sim_time(now))
        self._apply_event(name)
        self.faults_fired.append(f"event {name} at {self.body.travel_m:.3f} m")
        self._update_values()

    # ---- sensor values ---------------------------------------------------------------
    def _update_values(self) -> None:
        """The values every reply and frame reads until the next tick."""
        left, right = self.body.encoder_counts()
        values = dict.fromkeys(range(7, 59), 0)
        values.update(BATTERY)
        values[7] = self.bumps_drops
        for pid in self.cliffs:
            values[pid] = 1
        values[35] = int(self.mode) + self.config.mode_offset
        values[38] = len(self.stream_ids)
        values.update(self.requested)
        values[43], values[44] = left, right
        values[58] = 1 if self._forward_progress() else 0
        self.values = values

    def _forward_progress(self) -> bool:
        """Packet 58 bit 0 (p.32): 1 while making forward progress, always 0
        while turning, driving backward or not driving (C25: both wheels
        forward at the same speed)."""
        left, right = self.body.left, self.body.right
        return (
            self.body.moving
            and not (left.stalled or right.stalled)
            and left.speed_mm_s == right.speed_mm_s > 0.0
        )

    def _read_values(self, ids: tuple[int, ...]) -> dict[int, int]:
        """The values for a reply of ``ids``; 19 and 20, when asked, are the
        motion since each was itself last read (C11): reading one leaves the
        other's count alone."""
        values = dict(self.values)
        asked = {m for pid in ids for m in members(pid)}
        if 19 in asked:
            values[19] = self.body.take_distance()
        if 20 in asked:
            values[20] = self.body.take_angle(ANGLE_BUG_FACTOR if self.config.angle_bug else 1.0)
        return values

    # ---- commands --------------------------------------------------------------------
    def _execute(self, command: Command, now: float) -> None:
        op = command.opcode
        self._settle_mode(now)
        self._last_command_wall = now
        if not command.known:
            _LOG.info("unknown opcode %d skipped (C10)", op)
            self.unknown_opcodes += 1
            return
        if self.mode == Mode.OFF and op not in (Opcode.START, Opcode.RESET):
            _LOG.info("opcode %d ignored while the OI is Off", op)
            return
        if op in SENSOR_OPCODES:
            ids = (command.data[0],) if op == Opcode.SENSORS else tuple(command.data[1:])
            valid = tuple(pid for pid in ids if is_valid_id(pid))
            self._emit(now, encode_reply(valid, self._read_values(valid)))
            return
        self._execute_other(op, command.data, now)
        self.commands.append(
            CommandRecord(now - self.wall0, op, tuple(command.data), int(self.mode))
        )
        self._update_values_now()

    def _update_values_now(self) -> None:
        # mode and requested speeds show at once (a reply right after Safe says Safe)
        self.values[35] = int(self.mode) + self.config.mode_offset
        self.values.update(self.requested)
        self.values[38] = len(self.stream_ids)

    def _execute_other(self, op: int, data: bytes, now: float) -> None:
        if op == Opcode.RESET:
            self._enter_passive()
            self.mode = Mode.OFF
            self.stream_ids = ()
            self.stream_paused = False
            self.body.reset_encoders()
            self._emit(now, self._banner())
        elif op == Opcode.START:
            self._enter_passive()
        elif op == Opcode.STOP:
            self._enter_passive()
            self.mode = Mode.OFF
            self.stream_ids = ()
        elif op in (Opcode.SAFE, Opcode.CONTROL):
            self._change_mode(Mode.SAFE, now)
        elif op == Opcode.FULL:
            self._change_mode(Mode.FULL, now)
        elif op == Opcode.POWER:
            self._enter_passive()
            self.asleep = True
        elif op in (Opcode.SPOT, Opcode.CLEAN, Opcode.MAX_CLEAN, Opcode.SEEK_DOCK):
            self._enter_passive()
        elif op == Opcode.BAUD:
            if data[0] < len(BAUD_RATES):
                self.baud = BAUD_RATES[data[0]]
                self._baud_switch_until = now + BAUD_SWITCH_S
        elif op == Opcode.STREAM:
            ids = tuple(pid for pid in data[1:] if is_valid_id(pid))
            self.stream_ids = ids
            self.stream_paused = False
            budget = int(self.baud / 10 * STREAM_PERIOD_S)
            if ids and frame_size(ids) > budget:
                _LOG.warning(
                    "stream frame of %d bytes exceeds %d bytes per 15 ms at %d baud: "
                    "the stream will be corrupted",
                    frame_size(ids),
                    budget,
                    self.baud,
                )
        elif op == Opcode.PAUSE_RESUME:
            self.stream_paused = data[0] == 0
        elif op in ACTUATORS and self.mode in (Mode.SAFE, Mode.FULL):
            self._actuate(op, data)

    def _actuate(self, op: int, data: bytes) -> None:
        if op == Opcode.DRIVE:
            velocity, radius = decode_s16(data[0:2]), decode_s16(data[2:4])
            self.requested[39], self.requested[40] = velocity, radius
            self.body.set_wheels(*drive_wheels(velocity, radius))
        elif op == Opcode.DRIVE_DIRECT:
            right = max(-MAX_SPEED_MM_S, min(MAX_SPEED_MM_S, decode_s16(data[0:2])))
            left = max(-MAX_SPEED_MM_S, min(MAX_SPEED_MM_S, decode_s16(data[2:4])))
            self.requested[41], self.requested[42] = right, left
            self.body.set_wheels(float(right), float(left))
        elif op == Opcode.DRIVE_PWM:
            right_pwm = max(-MAX_PWM, min(MAX_PWM, decode_s16(data[0:2])))
            left_pwm = max(-MAX_PWM, min(MAX_PWM, decode_s16(data[2:4])))
            scale = MAX_SPEED_MM_S / MAX_PWM
            self.body.set_wheels(right_pwm * scale, left_pwm * scale)

    def _change_mode(self, mode: Mode, now: float) -> None:
        """Safe or Full, once the OI has had ``config.mode_change_s`` (C28)."""
        if self.config.mode_change_s <= 0.0:
            self.mode = mode
            self._pending_mode = None
        elif mode != self.mode or self._pending_mode is not None:
            self._pending_mode = (mode, now + self.config.mode_change_s)

    def _enter_passive(self) -> None:
        """Passive: wheels stop, requested speeds read 0 (C6, C15); at once,
        and a pending Safe or Full is dropped."""
        self.body.stop()
        self.mode = Mode.PASSIVE
        self._pending_mode = None
        for key in self.requested:
            self.requested[key] = 0

    def _banner(self) -> bytes:
        lines = ("bl-start", "STR730", self.config.firmware, "Roomba by iRobot!", "2016-03-03")
        return "".join(f"{line}\r\n" for line in lines).encode()

    # ---- safety events and faults -------------------------------------------------------
    def _apply_event(self, name: str) -> None:
        body = self.body
        if name.startswith("wheel_drop"):
            side = name.removeprefix("wheel_drop")
            if side in ("", "_left"):
                self.bumps_drops |= WHEEL_DROP_LEFT
            if side in ("", "_right"):
                self.bumps_drops |= WHEEL_DROP_RIGHT
            if self.mode == Mode.SAFE:
                self._enter_passive()
        elif name.startswith("cliff"):
            self.cliffs |= set(CLIFF_IDS.values()) if name == "cliff" else {CLIFF_IDS[name]}
            right, left = body.right.speed_mm_s, body.left.speed_mm_s
            forward = right + left > 0
            tight = (
                right != left
                and abs(
                    0.5 * self.config.geometry.wheel_base_m * 1000 * (right + left) / (right - left)
                )
                < HALF_BASE_MM
            )
            if self.mode == Mode.SAFE and body.moving and (forward or tight):
                self._enter_passive()
        elif name.startswith("bump"):
            side = name.removeprefix("bump")
            if side in ("", "_left"):
                self.bumps_drops |= BUMP_LEFT
            if side in ("", "_right"):
                self.bumps_drops |= BUMP_RIGHT
        elif name == "charger":
            if self.mode == Mode.SAFE:
                self._enter_passive()
        elif name == "clear":
            self.bumps_drops = 0
            self.cliffs.clear()
        elif name == "wake" and self.asleep:
            self.asleep = False
            self.mode = Mode.OFF
            self.stream_ids = ()

    def _fire_faults(self, at: float) -> None:
        travel = self.body.travel_m
        if travel <= 0.0:
            return
        due = [f for f in self._pending_faults if travel >= f.at_m]
        for fault in due:
            self._pending_faults.remove(fault)
            self.faults_fired.append(f"{fault} fired at {travel:.3f} m")
            _LOG.info("fault %s fired at %.3f m", fault, travel)
            if fault.name in EVENTS:
                self._apply_event(fault.name)
            elif fault.name == "disconnect":
                self._out.append((at, DISCONNECT))
                self.disconnected = True
            elif fault.name == "mute":
                self.muted = True
            elif fault.name == "garble":
                self.garble_next = True
            elif fault.name == "stall":
                self.body.left.stalled = self.body.right.stalled = True
            elif fault.name == "drag":
                self.body.left.drag = self.body.right.drag = DRAG_FACTOR

    def _emit(self, at: float, data: bytes) -> None:
        if self.muted or self.disconnected or not data:
            return
        if self.garble_next:
            self.garble_next = False
            data = data[:-1] + bytes((data[-1] ^ 0x01,))
        # the send buffer drains at the line rate; what does not fit is lost (C26)
        byte_s = 10.0 / self.baud
        waiting = max(0.0, self._tx_free_at - at) / byte_s
        room = max(0, int(TX_BUFFER_BYTES - waiting + 1e-9))
        if room < len(data):
            self.dropped_out_bytes += len(data) - room
            data = data[:room]
        if not data:
            return
        self._tx_free_at = max(self._tx_free_at, at) + len(data) * byte_s
        if self.host_baud is not None and self.host_baud != self.baud:
            data = carried(data, self.baud, self.host_baud)  # the host reads garbage
            if not data:
                return
        self._out.append((at, data))


__all__ = ["Create2Engine", "Output", "drive_wheels"]
