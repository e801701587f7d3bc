"""The fake robot's body: three axes, the encoder pose and the TRUE pose.

Wire units inside (0.1 inch, 0.1 degree and their rates), simulated seconds.
The encoder pose is the ideal integration of the commanded motion
(x += d cos(steer), y += d sin(steer), CHOICE C8). The true pose (metres,
radians) is advanced by the science layer's discrete error model
(:func:`odohil.science.simulator.drive_straight`, one segment at a time by
:func:`fakes.nomad.segment.drive_segment`, which draws what it would, or many
at once by :func:`fakes.nomad.segment.drive_segments`, which draws the same):
translation in segments of at most ``segment_m`` encoder metres (see below);
steering rotations change the true heading exactly (in-place turns are error
free in Martinelli's model).

Segments lie at fixed distances along each straight leg (measured from the
axis position where the leg began, never summed step by step) and each one is
drawn by its own call, so the random numbers a segment uses do not depend on
how the wall clock happened to slice the motion into steps: a seed gives the
same true poses on every run. A leg ends when the translation stops or
reverses, or at every step of a move that steers while it translates; such
coupled moves are integrated in steps that follow the wall clock, so only
their true poses may vary (slightly) from run to run.
"""

from __future__ import annotations

import logging
import math

import numpy as np

from fakes.nomad.profile import Profile, plan_move, plan_velocity
from fakes.nomad.segment import drive_segments
from odohil.protocol.nomad import wire_units
from odohil.science.parameters import ErrorParameters
from odohil.science.simulator import DEFAULT_SEGMENT_M

_LOG = logging.getLogger(__name__)

TRANS, STEER, TURRET = 0, 1, 2
AXIS_NAMES = ("translation", "steering", "turret")
MAX_SPEED = (200, 450, 450)
"""Speed limits (CHOICE C9): 0.1 in/s, 0.1 deg/s, 0.1 deg/s."""
MAX_ACCEL = (300, 300, 300)
"""Acceleration limits (CHOICE C9): 0.1 in/s^2, 0.1 deg/s^2, 0.1 deg/s^2."""
POWER_ON_SPEED = (0, 0, 0)
"""Speeds at power-on: the host must send ``sp`` before ``pr`` moves anything (C8)."""
POWER_ON_ACCEL = MAX_ACCEL
WIRE_LIMIT = 32767
COUPLED_STEP_S = 0.02
"""Largest simulated step while translation and steering move together, s..."""
MAX_COUPLED_STEPS = 64
"""...unless one advance would need more steps than this (a high time scale): then
the steps grow, so that the robot keeps up with the wall clock."""
NEGLIGIBLE_REST_M = 1e-9
"""A leg's last partial segment shorter than this (m) is not driven: it is float
rounding of a leg that is a whole number of segments long."""


class Axis:
    """One motor axis: position (wire), velocity (wire/s), an optional profile."""

    def __init__(self) -> None:
        self.pos = 0.0
        self.vel = 0.0
        self.profile: Profile | None = None
        self.stuck = False

    @property
    def moving(self) -> bool:
        """True while a profile runs (the motor-status bit, ignoring faults)."""
        return self.profile is not None

    def settle(self, t: float) -> None:
        """Move the axis along its profile to simulated time ``t`` s."""
        if self.profile is None:
            return
        self.pos, self.vel, done = self.profile.at(t)
        if done:
            self.profile = None
            self.vel = 0.0

    def halt(self) -> None:
        """Stop at once where the axis is."""
        self.profile = None
        self.vel = 0.0

    def shift(self, offset: float) -> None:
        """Redefine the axis' coordinate by ``offset`` wire units (no physical motion)."""
        self.pos += offset
        if self.profile is not None:
            p = self.profile
            target = None if p.target is None else p.target + offset
            self.profile = Profile(p.t0, p.p0 + offset, p.v0, p.phases, target)


class RobotBody:
    """Physics of the fake Nomad 150 (see the module docstring)."""

    def __init__(
        self,
        params: ErrorParameters,
        rng: np.random.Generator,
        segment_m: float = DEFAULT_SEGMENT_M,
    ) -> None:
        self.params = params
        self.rng = rng
        self.segment_m = segment_m
        self.axes = (Axis(), Axis(), Axis())
        self.t = 0.0
        self.enc_x = 0.0
        self.enc_y = 0.0
        self.true_x = np.zeros(1)
        self.true_y = np.zeros(1)
        self.true_theta = np.zeros(1)
        self.leg_origin = 0.0
        """Translation-axis position (wire) where the current straight leg began."""
        self.leg_segments = 0
        """Whole segments of the current leg already driven."""
        self.speed = list(map(float, POWER_ON_SPEED))
        self.accel = list(map(float, POWER_ON_ACCEL))
        self.limp = False
        self._clamped = False

    # ---- time -------------------------------------------------------------
    def advance(self, t_end: float) -> None:
        """Run the physics up to simulated time ``t_end`` s."""
        step = max(COUPLED_STEP_S, (t_end - self.t) / MAX_COUPLED_STEPS)
        while self.t < t_end:
            coupled = self.axes[TRANS].moving and self.axes[STEER].moving
            step_end = min(t_end, self.t + step) if coupled else t_end
            self._step(step_end)

    def _step(self, t1: float) -> None:
        trans, steer = self.axes[TRANS], self.axes[STEER]
        trans0, steer0 = trans.pos, steer.pos
        for axis in self.axes:
            axis.settle(t1)
        self.t = t1
        d_trans = trans.pos - trans0
        d_steer = steer.pos - steer0
        if d_trans != 0.0:
            heading = wire_units.wire_to_radians(steer0 + 0.5 * d_steer)
            self._set_encoder_xy(
                self.enc_x + d_trans * math.cos(heading),
                self.enc_y + d_trans * math.sin(heading),
            )
            if (trans0 - self.leg_origin) * d_trans < 0.0:
                self._drive_leg(trans0, end_leg=True)  # reversed: the leg ended at trans0
        self._drive_leg(trans.pos, end_leg=d_steer != 0.0 or not trans.moving)
        if d_steer != 0.0:
            self.true_theta += wire_units.wire_to_radians(d_steer)

    def _drive_leg(self, position: float, end_leg: bool) -> None:
        """Drive the true pose along the current leg up to translation ``position`` (wire)."""
        seg = self.segment_m
        travelled_m = wire_units.wire_to_metres(position - self.leg_origin)
        due = int(abs(travelled_m) / seg)
        if due > self.leg_segments:
            self._drive(math.copysign(seg, travelled_m), due - self.leg_segments)
            self.leg_segments = due
        if end_leg:
            rest_m = abs(travelled_m) - self.leg_segments * seg
            if rest_m > NEGLIGIBLE_REST_M:
                self._drive(math.copysign(rest_m, travelled_m), 1)
            self.leg_origin = position
            self.leg_segments = 0

    def _drive(self, signed_segment_m: float, n: int) -> None:
        pose = (float(self.true_x[0]), float(self.true_y[0]), float(self.true_theta[0]))
        pose = drive_segments(pose, signed_segment_m, n, self.params, self.rng)
        self.true_x[0], self.true_y[0], self.true_theta[0] = pose

    def _set_encoder_xy(self, x: float, y: float) -> None:
        cx = min(max(x, -WIRE_LIMIT), WIRE_LIMIT)
        cy = min(max(y, -WIRE_LIMIT), WIRE_LIMIT)
        clamped = (cx, cy) != (x, y)
        if clamped and not self._clamped:
            _LOG.warning("encoder position clamped to +-%d (C7): %.1f, %.1f", WIRE_LIMIT, x, y)
        self._clamped = clamped
        self.enc_x, self.enc_y = cx, cy

    # ---- commands (at the current simulated time) --------------------------
    def set_speeds(self, values: tuple[int, int, int]) -> None:
        """``sp``: speeds for position moves, clamped to :data:`MAX_SPEED` (C9)."""
        self.speed = [float(min(abs(v), m)) for v, m in zip(values, MAX_SPEED, strict=True)]

    def set_accels(self, values: tuple[int, int, int]) -> None:
        """``ac``: accelerations, clamped to :data:`MAX_ACCEL` (C9)."""
        self.accel = [float(min(abs(v), m)) for v, m in zip(values, MAX_ACCEL, strict=True)]

    def move_to(self, index: int, target: float) -> bool:
        """Start a trapezoidal move of one axis to ``target`` (wire); False if it cannot move."""
        axis = self.axes[index]
        vmax, amax = self.speed[index], self.accel[index]
        if vmax <= 0.0 or amax <= 0.0:
            return False
        phases = plan_move(axis.pos, axis.vel, target, vmax, amax)
        axis.profile = Profile(self.t, axis.pos, axis.vel, phases, target) if phases else None
        self.limp = False
        return bool(phases)

    def move_relative(self, deltas: tuple[int, int, int]) -> None:
        """``pr``: each axis with a non-zero delta moves by it from where it is now."""
        for index, delta in enumerate(deltas):
            if delta != 0:
                self.move_to(index, self.axes[index].pos + delta)

    def set_velocity(self, index: int, value: int) -> None:
        """Velocity mode of one axis (``vm``), clamped to :data:`MAX_SPEED`."""
        axis = self.axes[index]
        limit = MAX_SPEED[index]
        target = float(min(max(value, -limit), limit))
        amax = self.accel[index]
        if amax <= 0.0 or (target == axis.vel and axis.profile is None):
            return
        axis.profile = Profile(self.t, axis.pos, axis.vel, plan_velocity(axis.vel, target, amax))
        self.limp = False

    def stop(self) -> None:
        """``st``: every axis brakes at its acceleration and holds (at once if that is 0)."""
        for index, axis in enumerate(self.axes):
            axis.stuck = False
            if axis.profile is None:
                continue
            amax = self.accel[index]
            if amax <= 0.0 or axis.vel == 0.0:
                axis.halt()
            else:
                axis.profile = Profile(
                    self.t, axis.pos, axis.vel, plan_velocity(axis.vel, 0.0, amax)
                )

    def go_limp(self) -> None:
        """``lp``: motors unpowered; every axis stops where it is."""
        for axis in self.axes:
            axis.halt()
            axis.stuck = False
        self.limp = True

    def define_position(self, x: int, y: int) -> None:
        """``dp``: the encoder position becomes (x, y) wire units; nothing moves."""
        self._set_encoder_xy(float(x), float(y))

    def define_angles(self, steer: int, turret: int) -> None:
        """``da``: the encoder angles become (steer, turret) wire units; nothing moves."""
        self.axes[STEER].shift(steer - self.axes[STEER].pos)
        self.axes[TURRET].shift(turret - self.axes[TURRET].pos)

    def zero_encoders(self) -> None:
        """End of ``zr``: x, y, steering and turret all read 0."""
        self.enc_x = self.enc_y = 0.0
        self.axes[STEER].shift(-self.axes[STEER].pos)
        self.axes[TURRET].shift(-self.axes[TURRET].pos)

    # ---- readings ----------------------------------------------------------
    @property
    def moving(self) -> bool:
        """True while any axis moves (or a fault keeps it reporting so)."""
        return any(axis.moving or axis.stuck for axis in self.axes)

    def motor_status(self) -> int:
        """bit0 translation, bit1 steering, bit2 turret active."""
        bits = 0
        for index, axis in enumerate(self.axes):
            if axis.moving or axis.stuck:
                bits |= 1 << index
        return bits

    def axis_idle(self, index: int) -> bool:
        """True if the axis neither moves nor is reported moving."""
        axis = self.axes[index]
        return not (axis.moving or axis.stuck)

    def encoder_wire(self) -> tuple[int, int, int, int]:
        """Reported x, y (clamped to +-32767, C7) and steer, turret (0..3599, C6)."""
        return (
            round(self.enc_x),
            round(self.enc_y),
            wire_units.wire_angle_in_turn(round(self.axes[STEER].pos)),
            wire_units.wire_angle_in_turn(round(self.axes[TURRET].pos)),
        )

    def velocities_wire(self) -> tuple[int, int, int]:
        """Reported translation, steering, turret velocities (wire units/s)."""
        t, s, r = (max(-WIRE_LIMIT, min(WIRE_LIMIT, round(axis.vel))) for axis in self.axes)
        return t, s, r

    def true_pose(self) -> tuple[float, float, float]:
        """True pose: x m, y m, heading rad (unwrapped) in the start frame."""
        return float(self.true_x[0]), float(self.true_y[0]), float(self.true_theta[0])
