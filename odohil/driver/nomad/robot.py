"""``NomadRobot``: one connection to a Nomad 150, with SI methods.

Strict request/reply; a motion command is never resent (CHOICE C11). After
any failed request the robot is resynchronised with ``gs`` and the error
names the last encoder pose; any failure during a motion, and Ctrl-C, sends
``st`` first. :meth:`NomadRobot.stop_and_confirm` sends ``st`` and waits, within
a bound, for the robot to report that it stands still.

Stale replies: the robot's timestamp (u32 ms) never goes backwards on one
connection, so a state packet older than the last one accepted is a late
reply to an earlier request; it is discarded (counted in
``link.stats.rejected_replies``) and the wait for the real reply goes on.
"""

from __future__ import annotations

import contextlib
import math
import time
from collections.abc import Callable, Iterator
from types import TracebackType

from odohil.driver import stopping
from odohil.driver.nomad.facts import NOMAD150_FACTS
from odohil.driver.nomad.link import (
    DEFAULT_BAUD,
    NORMAL_TIMEOUT_S,
    ZR_TIMEOUT_S,
    Link,
    open_port,
)
from odohil.driver.nomad.sample import EncoderSample
from odohil.driver.port import Port, no_answer, port_name
from odohil.errors import (
    DisconnectedError,
    OdohilError,
    OdohilTimeoutError,
    ParameterError,
    ProtocolError,
)
from odohil.protocol.nomad import messages as m
from odohil.protocol.nomad.codes import MOTION_CODES, STATE_REPLY_CODES, Code
from odohil.protocol.nomad.framing import Packet
from odohil.protocol.nomad.numbers import S16_MAX, U16_MAX
from odohil.protocol.nomad.replies import decode_reply
from odohil.protocol.nomad.state import N150_MASK, RobotState, StateMask, state_timestamp_ms
from odohil.protocol.nomad.wire_units import metres_to_wire, radians_to_wire, wire_angle_in_turn

WS_MAX_S = 255
_U32_WRAP = 1 << 32
_STATE_TYPES = frozenset(int(code) for code in STATE_REPLY_CODES)
_REQUEST_TYPES = frozenset(int(code) for code in Code if code != Code.NAK)
"""Reply TYPEs that answer some request (every request code; NAK answers any)."""
STOP_CONFIRM_TIMEOUT_S = 2.0
"""How long :meth:`NomadRobot.stop_and_confirm` waits for the robot to report it stands still, s."""
_STOP_POLL_S = 0.02
MIN_POLL_PERIOD_S = 0.002
"""The fastest ``gs`` polling while a motion runs, s (from one request to the
next). A real line is slower: a ``gs`` and its reply (54 bytes) take 14 ms at
the Nomad's fastest 38400 baud, so a real robot is polled as before. An
in-process fake answers in a tenth of a millisecond, and without this floor the
loop spun the CPU for the motion's whole wall time."""


def is_older_ms(candidate_ms: int, last_ms: int) -> bool:
    """Whether robot timestamp ``candidate_ms`` lies before ``last_ms`` (u32 ms,
    compared modulo 2**32 so that the wrap after 49.7 days is not "older")."""
    return (candidate_ms - last_ms) % _U32_WRAP >= _U32_WRAP // 2


def _wire_s16(value: int, what: str) -> int:
    if abs(value) > S16_MAX:
        raise ParameterError(f"{what} is {value} wire units, beyond the s16 range")
    return value


def _rate(value: float, to_wire: Callable[[float], int], what: str) -> int:
    # Rates use the same factor as the quantity: 0.1 in/s, 0.1 deg/s, ...
    if not math.isfinite(value) or value < 0:
        raise ParameterError(f"{what} must be finite and >= 0, got {value!r}")
    wire = to_wire(value)
    if wire > U16_MAX:
        raise ParameterError(f"{what} {value!r} is beyond the u16 wire range")
    return wire


NO_ANSWER_CHECK = (
    "that the robot is switched on, that its serial cable is on {port}, and that "
    "both ends run at the same rate (--baud or robot.toml [serial] baud; the Nomad "
    "speaks " + NOMAD150_FACTS.rates_text() + "); see docs/robot-link.md"
)
"""What to check when the Nomad does not answer at connect (``{port}``: its port)."""


class NomadRobot:
    """A connected Nomad 150 (context manager; :meth:`close` sends ``st``)."""

    def __init__(
        self, link: Link, mask: StateMask = N150_MASK, reply_timeout_s: float = NORMAL_TIMEOUT_S
    ) -> None:
        self._link = link
        self._reply_s = reply_timeout_s
        """First-byte wait of ordinary requests, s (``[serial] timeout_s``)."""
        self._mask = mask
        self._last: EncoderSample | None = None
        self._last_ms: int | None = None
        self._in_motion = False

    @classmethod
    def connect(cls, url: str, baud: int = DEFAULT_BAUD) -> NomadRobot:
        """Open ``url`` and check that the robot answers ``gs``.

        Raises ConnectionFailedError when the port does not open or the robot
        does not answer (ParameterError for an unsupported baud).
        """
        return cls.from_port(open_port(url, baud))

    @classmethod
    def from_port(
        cls, port: Port, url: str = "", reply_timeout_s: float | None = None
    ) -> NomadRobot:
        """Wrap an already open port (opened from ``url``, for messages) and
        check that the robot answers ``gs``; ``reply_timeout_s``: the
        first-byte wait of ordinary requests and the silence that aborts a
        reply, s (None: :data:`NORMAL_TIMEOUT_S`)."""
        reply_s = NORMAL_TIMEOUT_S if reply_timeout_s is None else reply_timeout_s
        robot = cls(Link(port, reply_s), reply_timeout_s=reply_s)
        try:
            robot.state()
        except OdohilError as exc:
            robot._link.close()
            baud = getattr(port, "baudrate", DEFAULT_BAUD)
            where = port_name(port, url)
            check = NO_ANSWER_CHECK.format(port=where)
            raise no_answer(NOMAD150_FACTS.label, where, baud, f"gs: {exc}", check) from exc
        return robot

    def __enter__(self) -> NomadRobot:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()

    @property
    def last_sample(self) -> EncoderSample | None:
        """The most recent encoder sample received, if any."""
        return self._last

    @property
    def link(self) -> Link:
        """The underlying request/reply link (for statistics)."""
        return self._link

    def close(self) -> None:
        """Send ``st`` (best effort), then close the port. Idempotent."""
        if self._link.closed:
            return
        with contextlib.suppress(OdohilError):
            self._request(m.St())
        self._link.close()

    # -- requests -------------------------------------------------------

    def _request(self, request: m.Request, first_byte_s: float | None = None) -> RobotState:
        code = request.code
        wait_s = self._reply_s if first_byte_s is None else first_byte_s
        packet = self._link.exchange(
            m.encode_request(request), wait_s, lambda p: self._answers(p, code)
        )
        reply = decode_reply(packet, request, self._mask)
        if not isinstance(reply, RobotState):  # pragma: no cover - state requests only
            raise TypeError(f"{request} does not answer with a state packet")
        self._last_ms = reply.timestamp_ms
        self._last = EncoderSample.from_state(reply, time.monotonic())
        return reply

    def _answers(self, packet: Packet, code: Code) -> bool:
        """False for a packet that is not the reply to request ``code``: the
        reply to another request (a second host on the line sent it: odohil's
        guardian stops the robot after its process was killed, and the robot's
        answer can reach the next process after its own request) or a stale
        state packet. A TYPE no request has stays a reply, which decode_reply
        refuses (UnexpectedReplyError)."""
        if packet.type != code and packet.type in _REQUEST_TYPES:
            return False
        return self._fresh(packet)

    def _fresh(self, packet: Packet) -> bool:
        """False for a state packet older than the last one accepted (a stale reply)."""
        if self._last_ms is None or packet.type not in _STATE_TYPES:
            return True
        try:
            timestamp_ms = state_timestamp_ms(packet.payload, self._mask)
        except ProtocolError:
            return True  # not a state packet after all: decode_reply says why
        return not is_older_ms(timestamp_ms, self._last_ms)

    def _call(self, request: m.Request, first_byte_s: float | None = None) -> EncoderSample:
        """One request; on failure stop if moving, resync with ``gs``, re-raise."""
        try:
            self._request(request, first_byte_s)
        except OdohilError as exc:
            raise self._recover(exc, request) from exc
        except BaseException:
            self._emergency_stop()
            raise
        assert self._last is not None
        return self._last

    def _recover(self, exc: OdohilError, request: m.Request) -> OdohilError:
        stopped = ""
        if self._in_motion or request.code in MOTION_CODES:
            stopped = " st sent;" if self._try(m.St()) else " st failed;"
        if isinstance(exc, DisconnectedError):
            where = "no resync (disconnected)"
        elif self._try(m.Gs()):
            where = f"resynced with gs, encoders at {self._pose()}"
        else:
            where = f"gs resync failed, last known encoders {self._pose()}"
        return type(exc)(f"{type(request).__name__} failed: {exc};{stopped} {where}")

    def _pose(self) -> str:
        return self._last.pose_text() if self._last else "unknown"

    def _try(self, request: m.Request) -> bool:
        if self._link.closed:
            return False
        try:
            self._request(request)
        except OdohilError:
            return False
        return True

    def _emergency_stop(self) -> None:
        self._try(m.St())

    @contextlib.contextmanager
    def _motion(self) -> Iterator[None]:
        """Within: any exception (and Ctrl-C) sends ``st`` before propagating
        (odohil/driver/stopping.py ``stop_on_failure``)."""
        self._in_motion = True
        try:
            with stopping.stop_on_failure(self._emergency_stop):
                yield
        finally:
            self._in_motion = False

    # -- SI interface ---------------------------------------------------

    def state(self) -> EncoderSample:
        """One ``gs``: the current encoder sample."""
        return self._call(m.Gs())

    def set_watchdog(self, seconds: float) -> None:
        """``conf_tm``: stop the robot after ``seconds`` (rounded up, 1..255)
        without a command; 0 turns the watchdog off."""
        if not math.isfinite(seconds) or not 0 <= seconds <= 255:
            raise ParameterError(f"watchdog must be 0..255 s, got {seconds!r}")
        self._call(m.ConfTm(math.ceil(seconds)))

    def set_speeds(self, trans_m_s: float, steer_rad_s: float, turret_rad_s: float) -> None:
        """``sp``: speeds for relative moves, m/s and rad/s."""
        self._call(
            m.Sp(
                _rate(trans_m_s, metres_to_wire, "translation speed"),
                _rate(steer_rad_s, radians_to_wire, "steering speed"),
                _rate(turret_rad_s, radians_to_wire, "turret speed"),
            )
        )

    def set_accelerations(
        self, trans_m_s2: float, steer_rad_s2: float, turret_rad_s2: float
    ) -> None:
        """``ac``: accelerations, m/s^2 and rad/s^2."""
        self._call(
            m.Ac(
                _rate(trans_m_s2, metres_to_wire, "translation acceleration"),
                _rate(steer_rad_s2, radians_to_wire, "steering acceleration"),
                _rate(turret_rad_s2, radians_to_wire, "turret acceleration"),
            )
        )

    def define_pose(self, x_m: float, y_m: float) -> None:
        """``dp``: call the current position (x, y), metres."""
        self._call(m.Dp(_wire_s16(metres_to_wire(x_m), "x"), _wire_s16(metres_to_wire(y_m), "y")))

    def define_angles(self, steer_rad: float, turret_rad: float) -> None:
        """``da``: call the current steering and turret angles these, radians."""
        self._call(
            m.Da(
                wire_angle_in_turn(radians_to_wire(steer_rad)),
                wire_angle_in_turn(radians_to_wire(turret_rad)),
            )
        )

    def move_relative_wire(self, trans: int, steer: int, turret: int = 0) -> m.Pr:
        """``pr`` in wire units (0.1 in, 0.1 deg); returns what was sent.

        The reply comes at once; wait with :meth:`wait_stopped` or
        :meth:`poll_until_stopped`. Never resent. ParameterError, before
        anything is sent, for a value beyond the s16 range or ``pr(0, 0, 0)``
        (a motion that does not move).
        """
        if trans == steer == turret == 0:
            raise ParameterError("pr(0, 0, 0) would not move the robot: nothing sent")
        request = m.Pr(
            _wire_s16(trans, "translation"),
            _wire_s16(steer, "steering"),
            _wire_s16(turret, "turret"),
        )
        with self._motion():
            self._call(request)
        return request

    def move_relative(self, trans_m: float, steer_rad: float, turret_rad: float = 0.0) -> m.Pr:
        """``pr``: move by trans_m metres and turn by steer_rad / turret_rad,
        rounded to whole wire units; returns the wire command actually sent.

        ParameterError, before anything is sent, when a non-zero value rounds
        to zero wire units (below 2.54 mm or 0.1 degree: the robot would not
        do it) or lies beyond the s16 range."""
        named = (("translation", trans_m), ("steering", steer_rad), ("turret", turret_rad))
        for what, value in named:
            if not math.isfinite(value):
                raise ParameterError(f"{what} must be finite, got {value!r}")
        wire = (metres_to_wire(trans_m), radians_to_wire(steer_rad), radians_to_wire(turret_rad))
        for (what, value), units in zip(named, wire, strict=True):
            if value != 0 and units == 0:
                raise ParameterError(
                    f"{what} {value:g} rounds to 0 wire units (0.1 inch or 0.1 degree): "
                    "the robot would not move; nothing sent"
                )
        return self.move_relative_wire(*wire)

    def wait_stopped(self, timeout_s: float) -> EncoderSample:
        """``ws`` on all axes until they stop; OdohilTimeoutError (after ``st``)
        if they still move after ``timeout_s``."""
        if not math.isfinite(timeout_s) or timeout_s < 0:
            raise ParameterError(f"timeout must be finite and >= 0 s, got {timeout_s!r}")
        deadline = time.monotonic() + timeout_s
        with self._motion():
            while True:
                left = max(0, math.ceil(deadline - time.monotonic()))
                chunk = min(WS_MAX_S, left)
                sample = self._call(m.Ws(True, True, True, chunk), first_byte_s=chunk + 1.0)
                if not sample.moving:
                    return sample
                if time.monotonic() >= deadline:
                    raise OdohilTimeoutError(
                        f"still moving after {timeout_s:g} s; stopped at {sample.pose_text()}"
                    )

    def poll_until_stopped(
        self, timeout_s: float, on_sample: Callable[[EncoderSample], None] | None = None
    ) -> EncoderSample:
        """Poll ``gs`` until no axis is active, no faster than every
        :data:`MIN_POLL_PERIOD_S`; each sample goes to ``on_sample``. The
        polling also feeds the watchdog. OdohilTimeoutError
        (after ``st``) if still moving after ``timeout_s``."""
        deadline = time.monotonic() + timeout_s
        with self._motion():
            while True:
                asked = time.monotonic()
                sample = self._call(m.Gs())
                if on_sample is not None:
                    on_sample(sample)
                if not sample.moving:
                    return sample
                now = time.monotonic()
                if now >= deadline:
                    raise OdohilTimeoutError(
                        f"still moving after {timeout_s:g} s; stopped at {sample.pose_text()}"
                    )
                rest = min(asked + MIN_POLL_PERIOD_S, deadline) - now
                if rest > 0.0:
                    time.sleep(rest)

    def stop(self) -> EncoderSample:
        """``st``: stop and hold position."""
        return self._call(m.St())

    def stop_and_confirm(self, timeout_s: float = STOP_CONFIRM_TIMEOUT_S) -> EncoderSample:
        """Send ``st``, then poll ``gs`` until the robot reports no axis active
        (odohil/driver/stopping.py ``stop_and_confirm``).

        A failed ``st`` is sent again while time is left (never after the line
        is gone). Returns the first sample that shows the robot standing still.

        Args:
            timeout_s: the whole bound, s (finite, >= 0).

        Raises:
            StopUnconfirmedError: the robot did not report that it stopped within
                ``timeout_s`` (line closed or cut, no or bad replies, still moving).
        """

        def ask(request: m.Request) -> Callable[[float], EncoderSample]:
            def send(left_s: float) -> EncoderSample:
                state = self._request(request, first_byte_s=min(self._reply_s, left_s))
                return EncoderSample.from_state(state, time.monotonic())

            return send

        return stopping.stop_and_confirm(
            timeout_s,
            stop=ask(m.St()),
            read=ask(m.Gs()),
            moving=lambda sample: sample.moving,
            where=lambda sample: sample.pose_text(),
            closed=lambda: self._link.closed,
            poll_s=_STOP_POLL_S,
            names=("St", "Gs"),
        )

    def limp(self) -> EncoderSample:
        """``lp``: motors unpowered."""
        return self._call(m.Lp())

    def zero(self) -> EncoderSample:
        """``zr``: zero the robot; waits up to 120 s for the reply."""
        with self._motion():
            return self._call(m.Zr(), first_byte_s=ZR_TIMEOUT_S)
