"""The fake Nomad 150: bytes in, bytes out, a body that moves in between.

The engine is transport-free: :meth:`NomadEngine.receive` takes the bytes the
host wrote, :meth:`NomadEngine.take_output` hands out the bytes (or the
disconnect marker) that are due, and :meth:`NomadEngine.poll` lets time pass.
Both the pty emulator and the ``fakerobot://`` pyserial port drive this one
class. All protocol details follow the Nomad serial facts document and
its CHOICEs C2-C12 (see docs/fake-robot.md).

Two clocks: motion, accelerations, ``zr`` and the robot timestamp run on the
simulated clock, ``time_scale`` times faster than wall time; the watchdog,
``ws`` timeouts, the 1 s silence rule and all fault delays are host-facing and
count wall seconds.
"""

from __future__ import annotations

import dataclasses
import heapq
import logging
import math
import time
from collections.abc import Callable
from dataclasses import dataclass

from fakes.nomad.body import MAX_ACCEL, MAX_SPEED, STEER, TRANS, TURRET, RobotBody
from fakes.nomad.config import EmulatorConfig
from fakes.nomad.faults import FaultPlan
from fakes.nomad.truth import MotionRecord, TruthSnapshot
from odohil.errors import FramingError, UnexpectedReplyError
from odohil.protocol.nomad import messages as m
from odohil.protocol.nomad.codes import Code
from odohil.protocol.nomad.framing import DecodeFault, Packet, PacketDecoder, encode_packet
from odohil.protocol.nomad.replies import (
    NAK_BYTES,
    BpReply,
    RaReply,
    RcReply,
    RvReply,
    SnReply,
    encode_bp_reply,
    encode_ra_reply,
    encode_rc_reply,
    encode_rv_reply,
    encode_sn_reply,
    encode_state_reply,
)
from odohil.protocol.nomad.state import N150_MASK, RobotState, StateMask
from odohil.science.simulator import make_rng

_LOG = logging.getLogger(__name__)

SILENCE_RESET_S = 1.0
"""A partial packet is dropped after this many wall seconds of silence (C3)."""
HOST_REPLY_WAIT_S = 1.0
"""How long Ndirect waits for the first reply byte, wall s (ws: timeout + 1; zr: 120)."""
ZR_HOST_WAIT_S = 120.0
LATE_EXTRA_S = 1.0
"""A late reply leaves this long after the host's wait has run out, wall s."""
SPLIT_PARTS = 3
SPLIT_PAUSE_S = 0.25
"""Pause between the chunks of a split reply, wall s (below the host's 1 s)."""
GARBAGE = bytes((0xFF, 0x00, 0x5C, 0x13, 0x37, 0xAA))
"""Bytes written before a reply by fault ``garbage``; no 0x01 among them."""
WRONG_TYPE = 100
"""TYPE byte of a reply under fault ``wrong-type`` (no command has it)."""
DISCONNECT_AFTER_S = 0.3
"""Longest wall delay from a motion's reply to the cut line (fault ``disconnect``)."""
WATCHDOG_FAULT_FRACTION = 0.5
"""Fault ``watchdog`` fires after this fraction of the motion's planned duration."""
VM_WATCHDOG_FAULT_S = 1.0
"""...or this many simulated seconds into an endless ``vm`` motion."""
NOISE_SENTENCES = (
    b"$GPGGA,123519,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,*47\r\n",
    b"$GPRMC,123519,A,4807.038,N,01131.000,E,022.4,084.4,230394,003.1,W*6A\r\n",
    b"$GPGSA,A,3,04,05,,09,12,,,24,,,,,2.5,1.3,2.1*39\r\n",
)
"""What fault ``noise`` writes, in turn: NMEA sentences, as a GPS on the wrong port
would (ASCII, so no 0x01 start byte among them)."""
NOISE_PERIOD_S = 0.2
"""Wall seconds between two noise sentences: never 1 s of silence, and below 480
bytes/s, so the line keeps up even at 4800 baud."""
MOTION_LOG_CODES = frozenset({Code.PR, Code.PA, Code.VM, Code.MV, Code.ZR, Code.ST, Code.LP})


class Disconnect:
    """Marker in the output stream: the transport must cut the line here."""

    def __repr__(self) -> str:
        return "Disconnect()"


DISCONNECT = Disconnect()
Output = bytes | Disconnect


@dataclass
class _PendingWs:
    axes: tuple[bool, bool, bool]
    deadline_wall: float
    request_wall: float
    faults: frozenset[str]


@dataclass
class _PendingZr:
    done_sim: float
    request_wall: float
    faults: frozenset[str]


class NomadEngine:
    """One fake Nomad 150 robot (see the module docstring).

    Args:
        config: its settings.
        clock: wall clock in seconds (monotonic); injectable for tests.
    """

    def __init__(self, config: EmulatorConfig, clock: Callable[[], float] = time.monotonic) -> None:
        self.config = config
        self.clock = clock
        self.wall0 = clock()
        self.mask: StateMask = N150_MASK
        self.body = RobotBody(config.params, make_rng(config.seed), config.segment_m)
        self._decoder = PacketDecoder()
        self._faults = FaultPlan(config.faults)
        self._out: list[tuple[float, int, Output]] = []
        self._seq = 0
        self._last_rx_wall: float | None = None
        self._watchdog_s = 0
        self._watchdog_from_wall = self.wall0
        self._watchdog_armed = False
        self._fault_stop_sim: float | None = None
        self._ws: _PendingWs | None = None
        self._zr: _PendingZr | None = None
        self.disconnected = False
        self._disconnect_scheduled = False
        self._noise_next_wall: float | None = None
        self._noise_count = 0
        self.motion_log: list[MotionRecord] = []
        self.faults_fired: list[str] = []
        self.conf_ser: tuple[int, int] | None = None
        self.sonar_order: tuple[int, ...] = tuple(range(16))

    # ---- clocks -------------------------------------------------------------
    def sim_time(self, wall: float) -> float:
        """Simulated seconds at wall time ``wall``."""
        return (wall - self.wall0) * self.config.time_scale

    def wall_time(self, sim: float) -> float:
        """Wall time at which the simulated clock reads ``sim``."""
        return self.wall0 + sim / self.config.time_scale

    # ---- transport interface -------------------------------------------------
    def receive(self, data: bytes) -> None:
        """Bytes written by the host, in any chunking."""
        now = self.clock()
        self.poll(now)
        if self.disconnected or not data:
            return
        self._last_rx_wall = now
        for item in self._decoder.feed(data):
            if isinstance(item, DecodeFault):
                self._on_decode_fault(item, now)
            else:
                self._on_packet(item, now)
        self._check_pending(now)

    def poll(self, now: float | None = None) -> None:
        """Let (wall) time pass up to ``now``: motion, watchdog, ws, zr, silence."""
        if now is None:
            now = self.clock()
        target = self.sim_time(now)
        while True:
            event = self._next_event_sim()
            if event is None or event > target:
                break
            self.body.advance(max(event, self.body.t))
            self._fire_events(event)
        self.body.advance(target)
        if (
            self._decoder.pending
            and self._last_rx_wall is not None
            and now - self._last_rx_wall > SILENCE_RESET_S
        ):
            dropped = self._decoder.reset()
            _LOG.info("dropped %d bytes of a partial packet after 1 s silence", len(dropped))
        self._check_pending(now)

    def take_output(self, now: float | None = None) -> list[Output]:
        """The writes that are due by ``now``, in order (a write is bytes or DISCONNECT)."""
        if now is None:
            now = self.clock()
        self.poll(now)
        due: list[Output] = []
        if self._noise_next_wall is not None:
            self._out.clear()
            while self._noise_next_wall <= now and not self.disconnected:
                due.append(NOISE_SENTENCES[self._noise_count % len(NOISE_SENTENCES)])
                self._noise_count += 1
                self._noise_next_wall += NOISE_PERIOD_S
            return due
        while self._out and self._out[0][0] <= now and not self.disconnected:
            item = heapq.heappop(self._out)[2]
            due.append(item)
            if isinstance(item, Disconnect):
                self.disconnected = True
                self._out.clear()
        return due

    def next_output_wall(self) -> float | None:
        """Wall time of the next scheduled write, if any."""
        if self._noise_next_wall is not None:
            return self._noise_next_wall
        return self._out[0][0] if self._out else None

    def truth(self, now: float | None = None) -> TruthSnapshot:
        """The true pose and logs (the side channel; never on the wire)."""
        self.poll(now)
        x_m, y_m, theta = self.body.true_pose()
        ex, ey, es, et = self.body.encoder_wire()
        return TruthSnapshot(
            sim_time_s=self.body.t,
            true_x_m=x_m,
            true_y_m=y_m,
            true_theta_rad=theta,
            encoder_x=ex,
            encoder_y=ey,
            encoder_steer=es,
            encoder_turret=et,
            moving=self.body.moving,
            motor_status=self.body.motor_status(),
            motion_log=tuple(self.motion_log),
            faults_fired=tuple(self.faults_fired),
            disconnected=self.disconnected or self._disconnect_scheduled,
        )

    def state(self) -> RobotState:
        """The robot's state as a state packet would report it now (wire units)."""
        ex, ey, es, et = self.body.encoder_wire()
        tv, sv, rv = self.body.velocities_wire()
        return RobotState(
            sonar=(self.config.sonar_inches,) * 16,
            bumper=0,
            x=ex,
            y=ey,
            steer=es,
            turret=et,
            trans_vel=tv,
            steer_vel=sv,
            turret_vel=rv,
            compass=0,
            motor_status=self.body.motor_status(),
            timestamp_ms=self._timestamp_ms(),
            voltage_cpu_raw=self.config.voltage_raw[0],
            voltage_motor_raw=self.config.voltage_raw[1],
        )

    # ---- events on the simulated clock ----------------------------------------
    def _watchdog_sim(self) -> float | None:
        if not self._watchdog_armed or self._watchdog_s <= 0:
            return None
        return self.sim_time(self._watchdog_from_wall + self._watchdog_s)

    def _next_event_sim(self) -> float | None:
        times = [t for t in (self._watchdog_sim(), self._fault_stop_sim) if t is not None]
        return min(times) if times else None

    def _fire_events(self, at_sim: float) -> None:
        watchdog = self._watchdog_sim()
        if watchdog is not None and watchdog <= at_sim:
            self._watchdog_armed = False
            if self.body.moving:
                _LOG.info("watchdog expired after %d s: stopping", self._watchdog_s)
                self._note_fault(f"watchdog expired (conf_tm {self._watchdog_s} s): stop")
            self._stop_motion()
        if self._fault_stop_sim is not None and self._fault_stop_sim <= at_sim:
            self._fault_stop_sim = None
            self._note_fault("watchdog fault fired: stop")
            self._stop_motion()

    def _stop_motion(self) -> None:
        self.body.stop()

    # ---- input -------------------------------------------------------------
    def _on_decode_fault(self, fault: DecodeFault, now: float) -> None:
        _LOG.info("input %s: %s", fault.kind, fault.data.hex(" "))
        if fault.kind in ("bad_checksum", "bad_end"):
            self._schedule(now, NAK_BYTES)

    def _on_packet(self, packet: Packet, now: float) -> None:
        try:
            request = m.decode_request(packet)
        except (UnexpectedReplyError, FramingError) as exc:
            _LOG.info("NAK: %s", exc)
            self._schedule(now, NAK_BYTES)
            return
        self._watchdog_from_wall = now
        self._watchdog_armed = True
        faults = self._faults.fire(request.code)
        for name in sorted(faults):
            self._note_fault(f"{name} on {request.code.name.lower()}")
        self._ws = None
        self._zr = None
        if "nak" in faults:
            self._schedule(now, NAK_BYTES)
            return
        if "noise" in faults and self._noise_next_wall is None:
            self._noise_next_wall = now
        if request.code in MOTION_LOG_CODES:
            args = tuple(int(v) for v in dataclasses.astuple(request))
            self.motion_log.append(MotionRecord(now - self.wall0, request.code.name.lower(), args))
        reply = self._execute(request, now, faults)
        if request.code in (Code.PR, Code.PA, Code.VM, Code.MV):
            self._motion_faults(faults, now)
        if reply is not None:
            self._emit(reply, faults, now, now + HOST_REPLY_WAIT_S)

    def _execute(self, req: m.Request, now: float, faults: frozenset[str]) -> bytes | None:
        body = self.body
        code = req.code
        match req:
            case m.Ac():
                body.set_accels((req.trans, req.steer, req.turret))
            case m.Sp():
                body.set_speeds((req.trans, req.steer, req.turret))
            case m.Pr():
                body.move_relative((req.trans, req.steer, req.turret))
            case m.Pa():
                # absolute angles; the translation axis has no absolute position
                body.move_to(STEER, float(req.steer))
                body.move_to(TURRET, float(req.turret))
            case m.Vm():
                for index, value in enumerate((req.trans, req.steer, req.turret)):
                    body.set_velocity(index, value)
            case m.Mv():
                self._execute_mv(req)
            case m.Ct():
                mask = StateMask.from_ct(req.mask)
                if not mask.supported:
                    return NAK_BYTES
                self.mask = mask
            case m.St():
                body.stop()
            case m.Lp():
                body.go_limp()
            case m.Dp():
                body.define_position(req.x, req.y)
            case m.Da():
                body.define_angles(req.steer, req.turret)
            case m.Zr():
                self._start_zero(now, faults)
                return None
            case m.ConfSn():
                self.sonar_order = req.order
            case m.ConfTm():
                self._watchdog_s = req.seconds
            case m.ConfSer():
                self.conf_ser = (req.port, req.baud)
            case m.Ws():
                if req.timeout_s > 0:
                    axes = (req.trans, req.steer, req.turret)
                    self._ws = _PendingWs(axes, now + req.timeout_s, now, faults)
                    return None
            case m.GetRc():
                ex, ey, es, et = body.encoder_wire()
                return encode_rc_reply(RcReply(ex, ey, es, et))
            case m.GetRv():
                return encode_rv_reply(RvReply(*body.velocities_wire()))
            case m.GetRa():
                accel = tuple(round(a) for a in body.accel)
                return encode_ra_reply(RaReply(accel[0], accel[1], accel[2]))
            case m.GetSn():
                sonar = (self.config.sonar_inches,) * 16
                return encode_sn_reply(SnReply(sonar, self._timestamp_ms()))
            case m.GetBp():
                return encode_bp_reply(BpReply(0, self._timestamp_ms()))
            case _:
                pass
        return encode_state_reply(code, self.state(), self.mask)

    def _execute_mv(self, req: m.Mv) -> None:
        body = self.body
        modes = (
            (req.trans_mode, req.trans),
            (req.steer_mode, req.steer),
            (req.turret_mode, req.turret),
        )
        for index, (mode, value) in enumerate(modes):
            if mode == 1:
                body.set_velocity(index, value)
            elif mode == 2 and value != 0:
                body.move_to(index, body.axes[index].pos + value)
            elif mode == 3:
                body.axes[index].halt()
            elif mode == 4:
                body.accel[index] = float(min(abs(value), MAX_ACCEL[index]))
            elif mode == 5:
                body.speed[index] = float(min(abs(value), MAX_SPEED[index]))
            elif mode == 6 and index != TRANS:
                body.move_to(index, float(value))
            elif mode in (7, 8):
                _LOG.info("mv mode %d (torque) ignored on axis %d", mode, index)

    def _start_zero(self, now: float, faults: frozenset[str]) -> None:
        """``zr``: turn steering and turret to the nearest whole turn at full speed."""
        body = self.body
        body.axes[TRANS].halt()
        for axis in body.axes:
            axis.stuck = False
        end = body.t
        for index in (STEER, TURRET):
            axis = body.axes[index]
            axis.halt()
            target = round(axis.pos / 3600.0) * 3600.0
            saved = body.speed[index], body.accel[index]
            body.speed[index], body.accel[index] = float(MAX_SPEED[index]), float(MAX_ACCEL[index])
            body.move_to(index, target)
            body.speed[index], body.accel[index] = saved
            if axis.profile is not None:
                end = max(end, axis.profile.end_time)
        done = max(end, body.t + self.config.zr_seconds)
        self._zr = _PendingZr(done, now, faults)

    def _motion_faults(self, faults: frozenset[str], now: float) -> None:
        body = self.body
        if "stuck" in faults:
            for axis in body.axes:
                if axis.moving:
                    axis.stuck = True
        ends = [a.profile.end_time for a in body.axes if a.profile is not None]
        end = max(ends) if ends else body.t
        if "watchdog" in faults:
            span = VM_WATCHDOG_FAULT_S if math.isinf(end) else end - body.t
            self._fault_stop_sim = body.t + WATCHDOG_FAULT_FRACTION * span
        if "disconnect" in faults:
            span_wall = (end - body.t) / self.config.time_scale if not math.isinf(end) else 1.0
            delay = min(DISCONNECT_AFTER_S, max(0.0, 0.5 * span_wall))
            self._disconnect_scheduled = True
            self._schedule(now + delay, DISCONNECT)

    # ---- pending replies ------------------------------------------------------
    def _check_pending(self, now: float) -> None:
        ws = self._ws
        if ws is not None:
            idle = all(
                not wanted or self.body.axis_idle(index) for index, wanted in enumerate(ws.axes)
            )
            if idle or now >= ws.deadline_wall:
                self._ws = None
                host_wait = ws.deadline_wall + HOST_REPLY_WAIT_S
                self._emit(
                    encode_state_reply(Code.WS, self.state(), self.mask), ws.faults, now, host_wait
                )
        zr = self._zr
        if zr is not None and self.body.t >= zr.done_sim and not self.body.moving:
            self._zr = None
            self.body.zero_encoders()
            host_wait = zr.request_wall + ZR_HOST_WAIT_S
            self._emit(
                encode_state_reply(Code.ZR, self.state(), self.mask), zr.faults, now, host_wait
            )

    # ---- output ----------------------------------------------------------------
    def _emit(
        self, reply: bytes, faults: frozenset[str], now: float, host_wait_until: float
    ) -> None:
        """Schedule ``reply`` with the reply faults applied (see faults.py)."""
        if "drop" in faults:
            return
        data = reply
        if "wrong-type" in faults:
            data = encode_packet(WRONG_TYPE, reply[4:-2])
        if "corrupt" in faults:
            flipped = bytearray(data)
            flipped[len(flipped) // 2] ^= 0xFF
            data = bytes(flipped)
        if "garbage" in faults:
            data = GARBAGE + data
        if "merge" in faults:
            data = data + NAK_BYTES
        if "stray" in faults:  # the answer to another host's st comes first
            data = encode_state_reply(Code.ST, self.state(), self.mask) + data
        at = now
        if "late" in faults:
            at = max(now, host_wait_until) + LATE_EXTRA_S
        if "split" in faults:
            step = math.ceil(len(data) / SPLIT_PARTS)
            for part in range(SPLIT_PARTS):
                chunk = data[part * step : (part + 1) * step]
                if chunk:
                    self._schedule(at + part * SPLIT_PAUSE_S, chunk)
        else:
            self._schedule(at, data)

    def _schedule(self, at: float, item: Output) -> None:
        heapq.heappush(self._out, (at, self._seq, item))
        self._seq += 1

    def _note_fault(self, text: str) -> None:
        self.faults_fired.append(text)

    def _timestamp_ms(self) -> int:
        return int(self.body.t * 1000.0) & 0xFFFF_FFFF
