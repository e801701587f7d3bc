"""Trials on the robot, forth-and-back or general paths: legs are ``pr(trans)``,
turns ``pr(0, steer)``.

Every step is checked before the first is sent (a leg in the wire's range,
:func:`~odohil.protocol.nomad.limits.leg_to_wire`; a turn of at least
:data:`MIN_TURN_WIRE`); an error names the step (``step 3 of 8``) and the
accepted range. After each step the encoders must end where the command says
(within a tolerance in wire units, from where the last step ended); otherwise
the robot is stopped and MotionError raised. Lengths and angles are realised
in whole wire units, the turns rounded on their running sum so that a closed
path's turns add up to whole turns (a 7-gon's 51.43 degrees go out as 514 or
515 tenths, 3600 in all); the record keeps what was actually commanded.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass

from odohil.driver.nomad.robot import NomadRobot
from odohil.driver.nomad.sample import EncoderSample
from odohil.driver.step_limit import StepLimit, step_limit
from odohil.errors import (
    MotionError,
    OdohilTimeoutError,
    ParameterError,
    StopUnconfirmedError,
)
from odohil.protocol.nomad.limits import leg_to_wire
from odohil.protocol.nomad.messages import Pr
from odohil.protocol.nomad.numbers import S16_MAX
from odohil.protocol.nomad.wire_units import (
    radians_to_wire,
    wire_angle_difference,
    wire_angle_in_turn,
    wire_to_radians,
)
from odohil.science import frames
from odohil.science.paths import Drivable, Leg, Step, check_trial_length
from odohil.units import wrap_angle

DEFAULT_TOLERANCE_WIRE = 2
MIN_TURN_WIRE = 20
"""Smallest |turn| the driver sends, wire units of 0.1 degree (2 degrees; a
circle of at most 180 sides): the wire's 0.1 degree is at most 5 % of it, and
a turn that does not happen fails the end-of-step check (2 units) by a wide
margin, as :data:`~odohil.protocol.nomad.limits.MIN_LEG_M` does for legs."""
DEFAULT_STEP_TIMEOUT_S = 120.0
DEFAULT_SPEEDS = (0.5, math.radians(45.0))
"""Translation m/s and steering rad/s for the run (within the N150 client maxima)."""
DEFAULT_ACCELERATIONS = (0.5, math.radians(30.0))
"""Translation m/s^2 and steering rad/s^2 for the run."""


@dataclass(frozen=True)
class MotionRecord:
    """What one trial commanded and what the encoders reported.

    Attributes:
        design: the trial driven (a forth-and-back design or a general path).
        commands: the ``pr`` commands sent, wire units, in order.
        samples: every encoder sample taken during the run, in time order.
        step_ends: the encoder sample at the end of each step.
        start, end: encoder samples before the first and after the last step.
        end_pose: encoder end pose relative to the start, in the start frame
            (x m, y m, heading change rad reduced to (-pi, pi]).
        started_s, ended_s: host monotonic times of the run, s.
    """

    design: Drivable
    commands: tuple[Pr, ...]
    samples: tuple[EncoderSample, ...]
    step_ends: tuple[EncoderSample, ...]
    start: EncoderSample
    end: EncoderSample
    end_pose: tuple[float, float, float]
    started_s: float
    ended_s: float

    @property
    def duration_s(self) -> float:
        """Wall time of the run, s."""
        return self.ended_s - self.started_s


def relative_pose(start: EncoderSample, end: EncoderSample) -> tuple[float, float, float]:
    """``end`` in the frame of ``start``: (x m, y m, heading change rad in (-pi, pi])."""
    x, y, turned = frames.relative_pose(
        (start.x_m, start.y_m, start.steer_rad), (end.x_m, end.y_m, end.steer_rad)
    )
    return (x, y, wrap_angle(turned))


def _check_step(
    robot: NomadRobot,
    before: EncoderSample,
    after: EncoderSample,
    cmd: Pr,
    tolerance: int,
    what: str = "",
) -> None:
    heading = wire_to_radians(before.steer_wire)
    want_x = before.x_wire + cmd.trans * math.cos(heading)
    want_y = before.y_wire + cmd.trans * math.sin(heading)
    want_steer = wire_angle_in_turn(before.steer_wire + cmd.steer)
    errors = (
        abs(after.x_wire - want_x),
        abs(after.y_wire - want_y),
        abs(wire_angle_difference(after.steer_wire, want_steer)),
    )
    if max(errors) > tolerance:
        robot.stop()
        raise MotionError(
            f"{what + ': ' if what else ''}pr({cmd.trans}, {cmd.steer}, {cmd.turret}) ended "
            f"at {after.pose_text()}, "
            f"expected x={want_x:.1f} y={want_y:.1f} steer={want_steer} "
            f"(tolerance {tolerance} wire units); robot stopped"
        )


def _step_name(index: int, n: int, step: Step) -> str:
    what = f"leg {step.length_m:g} m" if isinstance(step, Leg) else f"turn {step.angle_rad:g} rad"
    return f"{what} (step {index} of {n})"


def _wire_steps(design: Drivable) -> list[tuple[int, int]]:
    """Every step of ``design`` as (translation, steering) wire units, all
    checked before the first is sent; the turns rounded on their running sum
    (module docstring). ParameterError names the step and the accepted range."""
    steps: list[tuple[int, int]] = []
    path = design.path()
    check_trial_length(design.label(), path)
    path_steps = path.steps
    n = len(path_steps)
    turned = 0.0  # the turns so far, rad
    sent = 0  # the turns so far as sent, wire units
    for index, step in enumerate(path_steps, start=1):
        if isinstance(step, Leg):
            try:
                steps.append((leg_to_wire(step.length_m), 0))
            except ParameterError as exc:
                raise ParameterError(
                    f"{_step_name(index, n, step)} of {design.label()}: {exc}; nothing sent"
                ) from None
            continue
        turned += step.angle_rad
        steer = radians_to_wire(turned) - sent
        if abs(steer) < MIN_TURN_WIRE or abs(steer) > S16_MAX:
            raise ParameterError(
                f"{_step_name(index, n, step)} of {design.label()} is {steer} wire units of "
                f"0.1 degree; a turn must be {MIN_TURN_WIRE}..{S16_MAX} in magnitude "
                f"({MIN_TURN_WIRE / 10:g} to {S16_MAX / 10:g} degrees); nothing sent"
            )
        sent += steer
        steps.append((0, steer))
    return steps


def _step_limits(
    design: Drivable,
    speeds: tuple[float, float],
    accelerations: tuple[float, float],
    step_timeout_s: float,
) -> list[StepLimit]:
    """The time limit of each step (odohil/driver/step_limit.py), checked before
    anything is sent."""
    limits: list[StepLimit] = []
    path_steps = design.path().steps
    for index, step in enumerate(path_steps, start=1):
        what = _step_name(index, len(path_steps), step)
        if isinstance(step, Leg):
            size, speed, acceleration = (
                step.length_m,
                speeds[0],
                accelerations[0],
            )
        else:
            size, speed, acceleration = (
                step.angle_rad,
                speeds[1],
                accelerations[1],
            )
        limits.append(step_limit(what, size, speed, acceleration, step_timeout_s))
    return limits


def _poll_within(
    robot: NomadRobot, limit: StepLimit, record: Callable[[EncoderSample], None]
) -> EncoderSample:
    """Poll until the step ends; past its limit: ``st`` (sent by the robot's
    motion guard), the stop confirmed, OdohilTimeoutError naming the step."""
    try:
        return robot.poll_until_stopped(limit.limit_s, record)
    except OdohilTimeoutError as exc:
        try:
            robot.stop_and_confirm()
        except StopUnconfirmedError as unconfirmed:
            raise StopUnconfirmedError(f"{limit.expired_text()}; {unconfirmed}") from exc
        raise OdohilTimeoutError(f"{limit.expired_text()}: {exc}; stop confirmed") from exc


def drive_trial(
    robot: NomadRobot,
    design: Drivable,
    *,
    tolerance_wire: int = DEFAULT_TOLERANCE_WIRE,
    step_timeout_s: float = DEFAULT_STEP_TIMEOUT_S,
    speeds: tuple[float, float] = DEFAULT_SPEEDS,
    accelerations: tuple[float, float] = DEFAULT_ACCELERATIONS,
    on_sample: Callable[[EncoderSample], None] | None = None,
) -> MotionRecord:
    """Drive one trial of ``design`` (any :class:`~odohil.science.paths.Drivable`:
    its encoder path's legs and turns, one ``pr`` each) and record the encoders (gs polling).

    First sets ``speeds`` (translation m/s, steering rad/s) and
    ``accelerations`` (m/s^2, rad/s^2); a ``pr`` with zero speed would not move.

    Raises ParameterError before anything is sent, naming the step, when a leg
    is outside the wire's range (:func:`odohil.protocol.nomad.limits.check_leg_length_m`:
    at least 50 mm, at most 83.2 m) or a turn is under :data:`MIN_TURN_WIRE`
    (2 degrees) or over the s16 range; MotionError if
    a step ends off its commanded encoder pose, and whatever the robot raises
    (after ``st``) on protocol errors or timeouts, OdohilTimeoutError (the stop
    confirmed) when a step outlasts its time limit (its length at ``speeds``,
    odohil/driver/step_limit.py, at most ``step_timeout_s``). ``on_sample`` sees every
    sample taken: the one before the first step, then every poll
    (a step ends at the first sample that shows no axis active).
    """
    if tolerance_wire < 0:
        raise ParameterError(f"tolerance must be >= 0 wire units, got {tolerance_wire}")
    wire_steps = _wire_steps(design)
    limits = _step_limits(design, speeds, accelerations, step_timeout_s)
    samples: list[EncoderSample] = []
    commands: list[Pr] = []
    step_ends: list[EncoderSample] = []
    started = time.monotonic()
    robot.set_accelerations(accelerations[0], accelerations[1], accelerations[1])
    robot.set_speeds(speeds[0], speeds[1], speeds[1])

    def record(sample: EncoderSample) -> None:
        samples.append(sample)
        if on_sample is not None:
            on_sample(sample)

    start = robot.state()
    record(start)
    before = start

    for (trans, steer), limit in zip(wire_steps, limits, strict=True):
        cmd = robot.move_relative_wire(trans, steer, 0)
        commands.append(cmd)
        after = _poll_within(robot, limit, record)
        _check_step(robot, before, after, cmd, tolerance_wire, limit.what)
        step_ends.append(after)
        before = after
    end = before
    return MotionRecord(
        design=design,
        commands=tuple(commands),
        samples=tuple(samples),
        step_ends=tuple(step_ends),
        start=start,
        end=end,
        end_pose=relative_pose(start, end),
        started_s=started,
        ended_s=time.monotonic(),
    )
