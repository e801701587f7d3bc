"""``Create2Robot``: the iRobot Create 2 behind the session's ``Robot`` protocol.

What it sends (facts §3-§9 and the CHOICEs in protocols/create2/README.md):

- connect: wait after opening (1 s, C17), resynchronise the command parser
  (130 x Start, facts §9 and C10), pause any stream a previous host left
  (Pause/Resume ``150 0``, p.22), drop what is still arriving, then read the
  mode: it must be Passive; a robot that reports 2 there has the +1 mode bug
  (C7) and every later mode reading is corrected by it;
- arm: Safe (``131``; Full ``132`` only when asked), then a wait for the OI to
  change modes (100 ms, as libcreate; pycreate2 waits 0.5 s) and the mode read
  back until it is the one asked for (at most 0.5 s) before anything else is
  sent; refused while a cliff, wheel drop or bump is reported; then the
  stream of the driver's packets starts (``148``; or, with ``sampling="poll"``,
  every reading is a Query List): bench/create2_leg_end.py found streaming
  ends legs at least as tightly at 115200 and 19200 baud (BENCHMARKS.md);
- drive: any encoder path (odohil/science/paths.py: a forth-and-back design,
  a square, a polygon, a circle cut into short legs and turns): straight
  legs with Drive Direct (both wheels at the set speed), in-place turns with
  the wheels at opposite speeds; every step is checked before the first is
  sent (:data:`MIN_STEP_TOLERANCES`); each step ends on the encoder counts
  43/44 (deltas mod 65536, wrap-safe both ways) against targets counted from
  the trial's start, so a leg that ends a count long makes the next leg a
  count short, and a turn that ends a count short makes the next turn a count
  longer; near the end it slows to a crawl and stops ahead of the target by
  the distance the wheels cover while a reading is on its way. The end check
  splits the wheels' miss into its two motions: the mean of the wheels (what
  legs drive, made up by the next leg) and their half difference (what turns
  drive, made up by the next turn); each must be within the tolerance of the
  last step that drove it (:meth:`Create2Robot._drive_step`), so a leg that
  ended within its tolerance and a turn that ended within its own do not add
  up to a failure on one wheel;
- every reading during a motion is checked: a cliff, a wheel drop, a bump or
  a mode other than the armed one (the OI drops Safe to Passive on its own
  safety stops) stops the robot and raises SafetyStopError; encoders that do
  not move while the wheels are told to stop it with MotionError; any other
  failure, and Ctrl-C, stop it before the exception goes on;
- close: ``91 00 00 00 00``, ``96 00``, Start, Stop (C13): the OI ends Off.

The OI has no command watchdog (§8): a drive command holds until replaced,
so a host that dies mid-leg leaves the robot driving until a Safe-mode
safety stop. DriveSettings.watchdog_s cannot be honoured; docs/create2.md
says so.

Odometry: each reading's encoder deltas become wheel travels with the
description's counts per revolution and wheel diameter, and the pose
advances along their arc with its wheel base (libcreate's update, without
its wrap bug).
"""

from __future__ import annotations

import contextlib
import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from types import TracebackType
from typing import NoReturn

from odohil.driver import stopping
from odohil.driver.create2.facts import CREATE2_FACTS, CREATE2_GEOMETRY, STEP_TOLERANCE_M
from odohil.driver.create2.link import (
    REPLY_TIMEOUT_S,
    Create2Link,
    Reading,
    Sampling,
    open_port,
)
from odohil.driver.guardian import Guardian, start_guardian
from odohil.driver.odometry import DriveSettings, OdometrySample, TrialMotion
from odohil.driver.port import listens_at_open, no_answer
from odohil.driver.step_limit import StepLimit, step_limit
from odohil.errors import (
    ConnectionFailedError,
    MotionError,
    OdohilError,
    OdohilTimeoutError,
    ParameterError,
    SafetyError,
    SafetyStopError,
    StopUnconfirmedError,
)
from odohil.protocol.create2 import commands
from odohil.protocol.create2.commands import MAX_SPEED_MM_S
from odohil.protocol.create2.numbers import encoder_delta
from odohil.protocol.create2.opcodes import Mode
from odohil.science import frames
from odohil.science.diff_drive import DiffDriveGeometry, odometry_step
from odohil.science.paths import Drivable, Leg, Turn, check_trial_length
from odohil.science.robot_description import RobotSettings
from odohil.units import wrap_angle

NO_ANSWER_CHECK = (
    "that it is awake (press Clean: Passive sleeps after 5 minutes without a command), "
    "that the cable is in its mini-DIN port and on {port}, and that both ends run at the "
    "same rate (--baud or robot.toml [serial] baud; 115200 unless a Baud command or the "
    "Clean button changed it); see docs/create2.md, Wiring and Line rate"
)
"""What to check when the Create 2 does not answer at connect (``{port}``: its port)."""
OPEN_WAIT_S = 1.0
"""Wait after opening the port before the first byte, s (C17; libcreate)."""
MODE_WAIT_S = 0.02
"""Wait after Start, s (C17)."""
MODE_CHANGE_WAIT_S = 0.1
"""Wait after Safe or Full before reading the mode back, s: libcreate's wait
after a mode command (pycreate2 waits 0.5 s "so the bot has time to change modes")."""
MODE_CHANGE_TIMEOUT_S = 0.5
"""The mode must read as asked within this long of Safe or Full, s (pycreate2's wait)."""
CRAWL_MM_S = 40
"""Wheel speed for the last part of a step, mm/s."""
SLOW_HORIZON_S = 0.045
"""A step slows to the crawl when it is this long (at its current rate) from its end:
about two readings, so the crawl starts before the slow zone is crossed."""
STOP_LEAD_S = 0.012
"""Stop this long (at the current rate) before the target, plus the line time of
a reading: the wheels turn on while a reading is on its way (its values up to
15 ms old) and the stop goes out."""
RATE_WINDOW_S = 0.1
"""The wheels' rate is measured over this much time of readings, s..."""
RATE_MIN_SPAN_S = 0.025
"""...and over at least this much (before that, the previous rate holds), s."""
STILL_READINGS = 2
"""A robot is still when this many readings in a row show the same counts."""
STALL_S = 0.6
"""Encoders that have not moved for this long while the wheels should turn: a stall, s."""
MAX_ATTEMPTS = 3
"""A step that stopped short (a reading came late) is finished at the crawl, at most
this many drives in all."""
STEP_TOLERANCE_FRACTION = 0.01
"""...or this fraction of the step's wheel travel (beyond :data:`STEP_TOLERANCE_M`,
odohil/driver/create2/facts.py), when larger (a late stop on a
busy host; the next step's target makes up for it)."""
MIN_STEP_COUNTS = 10
"""Shortest step the backend drives, counts (4.4 mm at the Create 2's constants)."""
MIN_STEP_TOLERANCES = 2.0
"""Every step must turn the wheels at least this many times its end-of-step
tolerance (so a step that did not happen fails its end check by a wide margin):
with the Create 2's constants a turn of at least 0.17 rad (9.6 degrees; a circle
of at most 37 sides); a leg must also be within the facts' leg range (5 cm to
100 m, odohil/driver/create2/facts.py)."""
STOP_CONFIRM_TIMEOUT_S = 2.0
CLOSE_BYTES = (
    commands.drive_direct(0, 0)
    + commands.pause_resume(False)
    + commands.start()
    + commands.stop_oi()
)
"""Stop, pause any stream, Start, Stop (C13): the OI ends Off. Sent by :meth:`Create2Robot.close`,
and by the guardian (odohil/driver/guardian.py) if this process dies while armed."""
MAX_READING_COUNTS = 16384
"""Largest encoder change between two readings, counts (a quarter of the 16-bit
range, 7.3 m; the wheels turn about 17 counts in a 15 ms frame): a larger one,
or one against the wheels' direction beyond :data:`BACKWARD_JITTER_COUNTS`,
cannot be told from a wrap-around (readings lost, or a fake run so fast that
its wheels turn half the range between two frames) and ends the step."""
BACKWARD_JITTER_COUNTS = 20
"""Largest count change against the step's direction accepted between two readings."""


@dataclass(frozen=True)
class _Step:
    """One step as wheel-count targets: signs of the wheels and counts to go."""

    left_sign: int
    right_sign: int
    counts: float
    speed_mm_s: int
    what: str
    limit: StepLimit
    tolerance: float
    """How far (counts, per motion) the step may end from its target."""

    @property
    def is_turn(self) -> bool:
        """True for an in-place turn (the wheels opposite)."""
        return self.left_sign != self.right_sign


class Create2Robot:
    """A connected Create 2 (context manager; :meth:`close` stops it).

    Also the ``create2`` backend of the ``odohil.robots`` entry-point group
    (pyproject.toml; odohil/session/robots/registry.py): :meth:`open` and
    :attr:`facts`.

    Args:
        link: the open link.
        geometry: the description's counts per revolution, wheel diameter
            and wheel base.
        full_mode: drive in Full (no OI safety stops) instead of Safe.
    """

    facts = CREATE2_FACTS
    name = CREATE2_FACTS.name
    default_baud = CREATE2_FACTS.default_baud

    def __init__(
        self,
        link: Create2Link,
        geometry: DiffDriveGeometry | None = None,
        *,
        full_mode: bool = False,
    ) -> None:
        self._link = link
        self.geometry = geometry or CREATE2_GEOMETRY
        self.full_mode = full_mode
        self.mode_offset = 0
        self._armed = False
        self._commanded = False
        self._last: Reading | None = None
        self._pose = (0.0, 0.0, 0.0)
        self._origin = (0.0, 0.0, 0.0)
        self._counts_seen = 0
        self.guardian: Guardian | None = None
        """Sends :data:`CLOSE_BYTES` if this process dies between :meth:`arm` and :meth:`close`."""

    # ---- connection --------------------------------------------------------------
    @classmethod
    def connect(
        cls,
        url: str,
        *,
        baud: int = CREATE2_FACTS.default_baud,
        geometry: DiffDriveGeometry | None = None,
        full_mode: bool = False,
        sampling: Sampling = "stream",
        open_wait_s: float = OPEN_WAIT_S,
        reply_timeout_s: float = REPLY_TIMEOUT_S,
    ) -> Create2Robot:
        """Open ``url`` and bring the OI to Passive (module docstring);
        ``reply_timeout_s``: the longest wait for a reading, s.

        Raises ConnectionFailedError when the port does not open or the robot
        does not answer in Passive (asleep? BRC wiring, docs/create2.md).
        """
        link = Create2Link(open_port(url, baud), url, baud, sampling, reply_timeout_s)
        robot = cls(link, geometry, full_mode=full_mode)
        try:
            if not listens_at_open(link.port):
                time.sleep(open_wait_s)
            link.send(commands.RESYNC)
            time.sleep(MODE_WAIT_S)
            link.stop_stream()
            link.drain_input()
            raw = link.ask(commands.sensors(35), 1)[0]
            if raw not in (Mode.PASSIVE, Mode.PASSIVE + 1):
                raise ConnectionFailedError(
                    f"after Start the OI must be Passive (1), it reports mode {raw}"
                )
            robot.mode_offset = raw - Mode.PASSIVE
            robot._last = link.reading()
        except OdohilError as exc:
            link.close()
            if isinstance(exc, ConnectionFailedError):
                raise
            check = NO_ANSWER_CHECK.format(port=url)
            detail = f"Sensors 35 after Start: {exc}"
            raise no_answer(CREATE2_FACTS.label, url, baud, detail, check) from exc
        return robot

    @classmethod
    def open(
        cls,
        url: str,
        baud: int | None = None,
        robot: RobotSettings | None = None,
        *,
        reply_timeout_s: float | None = None,
    ) -> Create2Robot:
        """The backend entry: connect at ``baud`` (its default when None) with the
        description's ``[robot]`` constants and mode (defaults: the Create 2's),
        waiting ``reply_timeout_s`` for each reading (None: 1 s,
        ``REPLY_TIMEOUT_S``; the description's ``[serial] timeout_s``)."""
        settings = robot or RobotSettings(protocol=CREATE2_FACTS.name)
        if reply_timeout_s is not None:
            CREATE2_FACTS.check_reply_timeout(reply_timeout_s)
        return cls.connect(
            url,
            baud=cls.default_baud if baud is None else baud,
            geometry=settings.drive or CREATE2_GEOMETRY,
            full_mode=settings.full_mode,
            reply_timeout_s=REPLY_TIMEOUT_S if reply_timeout_s is None else reply_timeout_s,
        )

    @property
    def port(self) -> str:
        """The port URL."""
        return self._link.url

    @property
    def transport(self) -> object:
        """The open pyserial port (a ``fakecreate2://`` port carries the fake's truth)."""
        return self._link.port

    @property
    def link(self) -> Create2Link:
        """The underlying link (statistics, tests)."""
        return self._link

    def __enter__(self) -> Create2Robot:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()

    def close(self) -> None:
        """Stop, pause any stream, leave the OI Off (C13), close, release the
        guardian. Idempotent. If the close itself fails, the guardian stays: it
        stops the robot when this process ends."""
        if not self._link.closed:
            with contextlib.suppress(OdohilError):
                self._link.send(CLOSE_BYTES)
                self._link.drain()
            self._commanded = False
            self._link.close()
        if self.guardian is not None:
            self.guardian.release()

    # ---- readings and odometry ----------------------------------------------------
    def _read(self) -> Reading:
        reading = self._link.reading()
        previous = self._last
        if previous is not None:
            dl = encoder_delta(previous.left_counts, reading.left_counts)
            dr = encoder_delta(previous.right_counts, reading.right_counts)
            left_m, right_m = self.geometry.wheel_travel(dl, dr)
            self._pose = odometry_step(self._pose, left_m, right_m, self.geometry.wheel_base_m)
        self._last = reading
        return reading

    def _sample(self, reading: Reading, moved: bool) -> OdometrySample:
        x, y, turned = frames.relative_pose(self._origin, self._pose)
        return OdometrySample(
            host_time_s=reading.host_time_s,
            robot_time_s=reading.host_time_s,
            x_m=x,
            y_m=y,
            theta_rad=wrap_angle(turned),
            moving=moved or self._commanded,
            wire=(
                f"L={reading.left_counts} R={reading.right_counts} counts, "
                f"mode {reading.mode_raw - self.mode_offset}"
            ),
        )

    def _reading_sample(self) -> tuple[Reading, OdometrySample]:
        before = self._last
        reading = self._read()
        moved = before is not None and (
            before.left_counts != reading.left_counts or before.right_counts != reading.right_counts
        )
        return reading, self._sample(reading, moved)

    def odometry(self) -> OdometrySample:
        """Read the encoders now; the odometry pose."""
        return self._guarded(lambda: self._reading_sample()[1])

    def zero(self, pose: tuple[float, float, float] = (0.0, 0.0, 0.0)) -> OdometrySample:
        """The odometry reads ``pose`` (x m, y m, heading rad) here (host side:
        the OI's encoders cannot be zeroed without Reset)."""
        sample = self.odometry()
        px, py, pth = pose
        qx, qy, qth = self._pose
        oth = qth - pth
        c, s = math.cos(oth), math.sin(oth)
        self._origin = (qx - (c * px - s * py), qy - (s * px + c * py), oth)
        return self._sample(self._last or self._read(), sample.moving)

    # ---- modes and safety ------------------------------------------------------------
    @property
    def _drive_mode(self) -> Mode:
        return Mode.FULL if self.full_mode else Mode.SAFE

    def mode(self) -> Mode:
        """The OI mode now (packet 35, corrected for the +1 bug)."""
        reading = self._read()
        return Mode(min(3, max(0, reading.mode_raw - self.mode_offset)))

    def arm(self, settings: DriveSettings) -> OdometrySample:
        """Safe (or Full when the description asks), checked; refused on hazards.
        First the guardian starts (odohil/driver/guardian.py: if this process
        dies, :data:`CLOSE_BYTES` are sent)."""
        self._speeds(settings)
        if self.guardian is None:
            self.guardian = start_guardian(self._link.port, CLOSE_BYTES)
        opcode = commands.full() if self.full_mode else commands.safe()
        self._link.send(opcode)
        time.sleep(MODE_CHANGE_WAIT_S)
        deadline = time.monotonic() + MODE_CHANGE_TIMEOUT_S - MODE_CHANGE_WAIT_S
        while True:
            reading, sample = self._reading_sample()
            mode = reading.mode_raw - self.mode_offset
            if mode == self._drive_mode or time.monotonic() >= deadline:
                break
        if mode != self._drive_mode:
            raise SafetyError(
                f"the OI did not enter {self._drive_mode.name} within "
                f"{MODE_CHANGE_TIMEOUT_S:g} s (it reports mode {mode}); "
                "nothing moved"
            )
        hazards = reading.hazards()
        if hazards:
            self._link.send(commands.start())  # back to Passive: nothing may move
            raise SafetyStopError(
                f"the robot reports {', '.join(hazards)}: clear it before driving; "
                "nothing moved, OI back in Passive"
            )
        self._armed = True
        if self._link.sampling == "stream" and not self._link.streaming:
            self._link.start_stream()
        return sample

    def _check(self, reading: Reading) -> None:
        problems = reading.hazards()
        mode = reading.mode_raw - self.mode_offset
        if mode != self._drive_mode:
            name = Mode(mode).name if 0 <= mode <= 3 else str(mode)
            problems.append(f"OI mode {name} instead of {self._drive_mode.name}")
        if problems:
            self.stop()
            self._armed = False
            raise SafetyStopError(
                f"{', '.join(problems)} during the motion; robot told to stop at "
                f"{self._sample(reading, True).pose_text()}"
            )

    # ---- stopping ---------------------------------------------------------------------------
    def stop(self) -> None:
        """Drive Direct 0, 0 now, without waiting (best effort)."""
        self._commanded = False
        with contextlib.suppress(OdohilError):
            self._link.send(commands.drive_direct(0, 0))

    def _stop_then_read(self, left_s: float) -> OdometrySample:
        """Drive Direct 0, 0, then one reading (``left_s``: unused, a reading
        takes one frame)."""
        self.stop()
        return self._reading_sample()[1]

    def stop_and_confirm(self, timeout_s: float = STOP_CONFIRM_TIMEOUT_S) -> OdometrySample:
        """Stop, then read until the counts stand still; StopUnconfirmedError if
        not (odohil/driver/stopping.py ``stop_and_confirm``)."""
        return stopping.stop_and_confirm(
            timeout_s,
            stop=self._stop_then_read,
            read=lambda _left_s: self._reading_sample()[1],
            moving=lambda sample: sample.moving,
            where=lambda sample: sample.pose_text(),
            closed=lambda: self._link.closed,
            still_readings=STILL_READINGS - 1,  # a sample's "moving" compares two readings
        )

    def settle(self, timeout_s: float) -> OdometrySample:
        """Stop if the encoders move and wait until they stand still, within
        ``timeout_s`` (odohil/driver/stopping.py ``settle``)."""
        return stopping.settle(
            timeout_s,
            read=self.odometry,
            moving=lambda sample: sample.moving,
            confirm=self.stop_and_confirm,
        )

    def _guarded(self, action: Callable[[], OdometrySample]) -> OdometrySample:
        with stopping.stop_on_failure(self.stop, when=lambda: self._commanded):
            return action()

    # ---- driving -------------------------------------------------------------------------------
    def _speeds(self, settings: DriveSettings) -> tuple[int, int]:
        """Leg and turn wheel speeds, mm/s, checked."""
        leg = round(settings.speed_m_s * 1000.0)
        turn = round(settings.turn_rate_rad_s * self.geometry.wheel_base_m / 2.0 * 1000.0)
        limit = MAX_SPEED_MM_S / 1000.0
        if not (math.isfinite(settings.speed_m_s) and 1 <= leg <= MAX_SPEED_MM_S):
            raise ParameterError(
                f"speed_m_s must be in [0.001, {limit:g}] m/s for the Create 2, "
                f"got {settings.speed_m_s!r}"
            )
        if not (math.isfinite(settings.turn_rate_rad_s) and 1 <= turn <= MAX_SPEED_MM_S):
            most = limit / (self.geometry.wheel_base_m / 2.0)
            raise ParameterError(
                f"turn_rate_rad_s must give wheel speeds of 1..{MAX_SPEED_MM_S} mm/s: "
                f"(0, {most:.2f}] rad/s at wheel base {self.geometry.wheel_base_m:g} m, "
                f"got {settings.turn_rate_rad_s!r}"
            )
        if not (math.isfinite(settings.step_timeout_s) and settings.step_timeout_s > 0):
            raise ParameterError(
                f"step_timeout_s must be positive, got {settings.step_timeout_s!r}"
            )
        return leg, turn

    def _tolerance(self, counts: float) -> float:
        """End-of-step tolerance of a step of ``counts`` wheel counts, counts."""
        return max(self.geometry.counts_for(STEP_TOLERANCE_M), STEP_TOLERANCE_FRACTION * counts)

    def _steps(self, design: Drivable, settings: DriveSettings) -> list[_Step]:
        """Every step of ``design`` as wheel targets, all checked before the first
        is sent: ParameterError naming the step and the accepted range."""
        leg_speed, turn_speed = self._speeds(settings)
        path = design.path()
        check_trial_length(design.label(), path)
        path_steps = path.steps
        n = len(path_steps)
        steps: list[_Step] = []
        half_base = self.geometry.wheel_base_m / 2.0
        for index, step in enumerate(path_steps, start=1):
            if isinstance(step, Leg):
                sign = 1 if step.length_m > 0 else -1
                counts = self.geometry.counts_for(abs(step.length_m))
                what = f"leg {step.length_m:g} m"
                size, speed, acceleration = (
                    step.length_m,
                    settings.speed_m_s,
                    settings.acceleration_m_s2,
                )
                left_sign, right_sign, wheel_speed = sign, sign, leg_speed
            else:
                assert isinstance(step, Turn)
                if step.kind != "spin":
                    raise ParameterError(
                        f"step {index} of {n} of {design.label()}: turn {step.angle_rad:g} rad "
                        f"is an {step.kind} turn (a curve's heading change); the Create 2 "
                        "backend turns in place only, and a spin's turn error would be "
                        "taken for an arc's; nothing sent"
                    )
                sign = 1 if step.angle_rad > 0 else -1
                counts = self.geometry.counts_for(abs(step.angle_rad) * half_base)
                what = f"turn {step.angle_rad:g} rad"
                size, speed, acceleration = (
                    step.angle_rad,
                    settings.turn_rate_rad_s,
                    settings.turn_acceleration_rad_s2,
                )
                left_sign, right_sign, wheel_speed = -sign, sign, turn_speed
            tolerance = self._tolerance(counts)
            least = max(MIN_STEP_COUNTS, MIN_STEP_TOLERANCES * tolerance)
            if isinstance(step, Leg) and not (
                CREATE2_FACTS.min_leg_m <= abs(step.length_m) <= CREATE2_FACTS.max_leg_m
            ):
                raise ParameterError(
                    f"step {index} of {n} of {design.label()}: {what}; a leg must be "
                    f"{CREATE2_FACTS.min_leg_m:g} m to {CREATE2_FACTS.max_leg_m:g} m long "
                    "(odohil/driver/create2/facts.py); nothing sent"
                )
            if counts < least:
                least_m = least * self.geometry.metres_per_count
                accepted = (
                    f"|angle| >= {least_m / half_base:.3g} rad "
                    f"({math.degrees(least_m / half_base):.3g} degrees)"
                    if isinstance(step, Turn)
                    else f"|length| >= {least_m:.3g} m"
                )
                raise ParameterError(
                    f"step {index} of {n} of {design.label()}: {what} turns each wheel "
                    f"{counts:.1f} encoder counts; at least {least:.0f} ({accepted}: "
                    f"{MIN_STEP_TOLERANCES:g} x its end-of-step tolerance of "
                    f"{tolerance:.0f} counts); nothing sent"
                )
            what = f"{what} (step {index} of {n})"
            limit = step_limit(what, size, speed, acceleration, settings.step_timeout_s)
            steps.append(_Step(left_sign, right_sign, counts, wheel_speed, what, limit, tolerance))
        return steps

    def drive(
        self,
        design: Drivable,
        settings: DriveSettings,
        on_sample: Callable[[OdometrySample], None] | None = None,
    ) -> TrialMotion:
        """Drive one trial of ``design`` (module docstring); stops the robot
        before raising on any failure."""
        steps = self._steps(design, settings)
        if not self._armed:
            raise SafetyError("arm() the robot before driving: it is not in Safe or Full")
        samples: list[OdometrySample] = []

        def record(sample: OdometrySample) -> None:
            samples.append(sample)
            if on_sample is not None:
                on_sample(sample)

        with self._motion():
            started = time.monotonic()
            reading, start = self._reading_sample()
            self._check(reading)
            record(start)
            travelled = [0.0, 0.0]  # signed counts since the trial's start
            target = [0.0, 0.0]
            # how far the wheels' mean (legs) and half difference (turns) may be
            # from their targets: the tolerance of the last step that drove each
            allowed = [self._tolerance(0.0), self._tolerance(0.0)]
            for step in steps:
                target[0] += step.left_sign * step.counts
                target[1] += step.right_sign * step.counts
                allowed[1 if step.is_turn else 0] = step.tolerance
                self._drive_step(step, target, travelled, allowed, record)
            end = samples[-1]
        return TrialMotion(
            design=design,
            samples=tuple(samples),
            start=start,
            end=end,
            end_pose=_relative(start, end),
            started_s=started,
            ended_s=time.monotonic(),
        )

    def _motion(self) -> contextlib.AbstractContextManager[None]:
        return stopping.stop_on_failure(self.stop)

    def _drive_step(
        self,
        step: _Step,
        target: list[float],
        travelled: list[float],
        allowed: list[float],
        record: Callable[[OdometrySample], None],
    ) -> None:
        """Drive one step to its target (counted from the trial's start) and check
        where it ended: the wheels' mean and half difference each within
        ``allowed`` (counts: the tolerance of the last leg, of the last turn)."""
        signs = (step.left_sign, step.right_sign)

        def remaining() -> float:
            return sum(s * (t - d) for s, t, d in zip(signs, target, travelled, strict=True)) / 2

        crawl = min(step.speed_mm_s, CRAWL_MM_S)
        deadline = time.monotonic() + step.limit.limit_s
        tolerance = step.tolerance
        speed = step.speed_mm_s
        for _attempt in range(MAX_ATTEMPTS):
            last = self._run_to_target(step, speed, crawl, remaining, travelled, deadline, record)
            # wait until the wheels stand still, then check where the step ended
            still = 0
            while still < STILL_READINGS - 1:
                previous = last
                reading, sample = self._reading_sample()
                last = reading
                record(sample)
                self._check(reading)
                self._track(step, previous, reading, travelled)
                moved = (previous.left_counts, previous.right_counts) != (
                    reading.left_counts,
                    reading.right_counts,
                )
                still = 0 if moved else still + 1
                if time.monotonic() > deadline:
                    raise StopUnconfirmedError(f"{step.what}: the wheels still turn after the stop")
            if remaining() <= tolerance:
                break
            speed = crawl  # stopped short (a late reading): finish at the crawl
        off = [t - d for t, d in zip(target, travelled, strict=True)]
        mean, half_difference = (off[0] + off[1]) / 2, (off[1] - off[0]) / 2
        if abs(mean) > allowed[0] or abs(half_difference) > allowed[1]:
            metres = self.geometry.metres_per_count
            raise MotionError(
                f"{step.what} ended {off[0]:+.0f} (left), {off[1]:+.0f} (right) counts "
                f"from its target: the wheels' mean {mean:+.0f} counts (legs; tolerance "
                f"{allowed[0]:.0f} counts, {allowed[0] * metres:.3g} m), their half "
                f"difference {half_difference:+.0f} counts (turns; tolerance {allowed[1]:.0f} "
                f"counts, {allowed[1] * metres:.3g} m per wheel); robot stopped"
            )

    def _run_to_target(
        self,
        step: _Step,
        speed: int,
        crawl: int,
        remaining: Callable[[], float],
        travelled: list[float],
        deadline: float,
        record: Callable[[OdometrySample], None],
    ) -> Reading:
        """Drive the step's wheels until the target is (about to be) reached,
        then stop; the last reading."""
        last = self._last
        assert last is not None
        # counts per second along the step: the commanded speed's until the
        # readings span RATE_MIN_SPAN_S, measured from then on
        rate = speed / (1000.0 * self.geometry.metres_per_count)
        # (robot time, -remaining) at this speed, from the reading before the
        # command: a short step at a fast rate (a fake run fast) knows its rate
        # from its second reading on, in time to slow down
        history: list[tuple[float, float]] = [(last.robot_time_s, -remaining())]
        lead_s = STOP_LEAD_S + self._link.transfer_s
        moved_at = time.monotonic()
        if remaining() > 0:
            self._command(step, speed)
        while self._commanded:
            previous = last
            reading, sample = self._reading_sample()
            last = reading
            record(sample)
            self._check(reading)
            self._track(step, previous, reading, travelled)
            now = reading.host_time_s
            if (previous.left_counts, previous.right_counts) != (
                reading.left_counts,
                reading.right_counts,
            ):
                moved_at = now
            history.append((reading.robot_time_s, -remaining()))
            rate = _rate(history, rate)
            left_to_go = remaining()
            if left_to_go <= rate * lead_s or left_to_go <= 0:
                self.stop()
                break
            if speed > crawl and left_to_go <= rate * SLOW_HORIZON_S:
                self._command(step, crawl)
                history.clear()
                rate *= crawl / speed
                speed = crawl
            if now - moved_at > STALL_S:
                self.stop()
                raise MotionError(
                    f"{step.what}: the encoders have not moved for {STALL_S:g} s while the "
                    f"wheels were told to turn (stalled or held?); robot told to stop at "
                    f"{sample.pose_text()}"
                )
            if now > deadline:
                self._end_step(
                    f"{step.limit.expired_text()}; robot told to stop at {sample.pose_text()}"
                )
        return last

    def _track(
        self, step: _Step, previous: Reading, reading: Reading, travelled: list[float]
    ) -> None:
        """Add the counts since ``previous`` to ``travelled``; a change the 16-bit
        counters cannot tell from a wrap-around (:data:`MAX_READING_COUNTS`) ends the step."""
        deltas = (
            encoder_delta(previous.left_counts, reading.left_counts),
            encoder_delta(previous.right_counts, reading.right_counts),
        )
        signs = (step.left_sign, step.right_sign)
        if any(
            abs(d) > MAX_READING_COUNTS or s * d < -BACKWARD_JITTER_COUNTS
            for d, s in zip(deltas, signs, strict=True)
        ):
            self.stop()
            raise MotionError(
                f"{step.what}: the encoders changed by {deltas[0]:+d} (left), {deltas[1]:+d} "
                f"(right) counts between two readings, against the wheels' direction or more "
                f"than {MAX_READING_COUNTS}: a wrap-around of the 16-bit counters cannot be "
                "ruled out (readings lost, or a fake whose time scale turns its wheels half "
                "the counter range between two frames); robot told to stop"
            )
        travelled[0] += deltas[0]
        travelled[1] += deltas[1]

    def _end_step(self, message: str) -> NoReturn:
        """Stop, confirm the stop, and raise OdohilTimeoutError with ``message``
        (StopUnconfirmedError, with it, when the robot does not report still)."""
        try:
            self.stop_and_confirm(STOP_CONFIRM_TIMEOUT_S)
        except StopUnconfirmedError as exc:
            raise StopUnconfirmedError(f"{message}; {exc}") from exc
        raise OdohilTimeoutError(f"{message}; stop confirmed")

    def _command(self, step: _Step, speed: int) -> None:
        self._commanded = True
        self._link.send(commands.drive_direct(step.right_sign * speed, step.left_sign * speed))


def _rate(history: list[tuple[float, float]], previous: float) -> float:
    """Counts per second over the readings of the last :data:`RATE_WINDOW_S`
    (readings can arrive bunched: one interval alone says little); the
    previous rate while they span less than :data:`RATE_MIN_SPAN_S`."""
    now = history[-1][0]
    while len(history) > 2 and now - history[1][0] >= RATE_WINDOW_S:
        del history[0]
    span = now - history[0][0]
    if span < RATE_MIN_SPAN_S:
        return previous
    return max(0.0, (history[-1][1] - history[0][1]) / span)


def _relative(start: OdometrySample, end: OdometrySample) -> tuple[float, float, float]:
    """``end`` in the frame of ``start``: (x m, y m, heading change rad in (-pi, pi])."""
    x, y, turned = frames.relative_pose(
        (start.x_m, start.y_m, start.theta_rad), (end.x_m, end.y_m, end.theta_rad)
    )
    return (x, y, wrap_angle(turned))
