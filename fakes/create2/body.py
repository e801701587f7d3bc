"""The fake Create 2's body: two wheels, their encoders and the TRUE pose.

OI units at the wheels (mm, mm/s), simulated seconds. The encoders count the
commanded wheel travel with the nominal constants (CHOICE C4, C5: integer
ticks with the fraction carried, in the commanded direction, stops instant);
the true pose follows the differential drive's error model of
odohil/science/diff_drive.py: the translation of each step goes through the
paper's discrete model with :meth:`DiffDriveErrors.straight_parameters`
(:func:`odohil.science.simulator.drive_straight`), its rotation through
:func:`odohil.science.diff_drive.spin`.

Straight legs are cut into segments at fixed encoder distances from the
leg's start (as the fake Nomad's body does), so a seed gives the same true
poses whatever the wall clock's slicing; a leg ends whenever the wheel
commands change.
"""

from __future__ import annotations

import math

import numpy as np

from odohil.science.diff_drive import DiffDriveErrors, DiffDriveGeometry, spin
from odohil.science.simulator import drive_straight

NEGLIGIBLE_REST_M = 1e-9
COUNTS_MODULUS = 65536


class Wheel:
    """One wheel: commanded speed (mm/s) and its encoder (counts)."""

    def __init__(self, origin_counts: int) -> None:
        self.speed_mm_s = 0.0
        self.counts = origin_counts
        self.fraction = 0.0
        self.stalled = False
        self.drag = 1.0  # fraction of the commanded speed the wheel really turns at

    def turn(self, travel_mm: float, mm_per_count: float) -> None:
        """The encoder counts ``travel_mm``, in the commanded direction (C5)."""
        ticks = self.fraction + abs(travel_mm) / mm_per_count
        whole = math.floor(ticks)
        self.fraction = ticks - whole
        self.counts += whole if self.speed_mm_s >= 0.0 else -whole


class Create2Body:
    """Physics of the fake Create 2 (module docstring).

    Args:
        errors: how the true robot differs from its nominal constants.
        geometry: the nominal constants the encoders count with.
        rng: the noise generator.
        segment_m: longest segment of the discrete error model, encoder metres.
        encoder_origin: encoder counts at power-on and after Reset (C3).
    """

    def __init__(
        self,
        errors: DiffDriveErrors,
        geometry: DiffDriveGeometry,
        rng: np.random.Generator,
        segment_m: float,
        encoder_origin: int = 0,
    ) -> None:
        self.errors = errors
        self.params = errors.straight_parameters()
        self.geometry = geometry
        self._motion_seed = int(rng.integers(2**63))
        self.motions = 0
        """Motions ended so far (wheels brought to rest from moving)."""
        self.rng = self._motion_rng()
        self.segment_m = segment_m
        self.encoder_origin = encoder_origin
        self.left = Wheel(encoder_origin)
        self.right = Wheel(encoder_origin)
        self.t = 0.0
        self.true_x = np.zeros(1)
        self.true_y = np.zeros(1)
        self.true_theta = np.zeros(1)
        self.leg_travel_m = 0.0
        self.leg_segments = 0
        self.travel_m = 0.0
        """Total encoder distance driven (mean of the wheels' |travel|), m."""
        self.distance_mm = 0.0
        self.angle_deg = 0.0
        """Motion since packet 19 (distance) and 20 (angle) were each last read (C11), nominal."""

    # ---- commands -------------------------------------------------------------
    def set_wheels(self, right_mm_s: float, left_mm_s: float) -> None:
        """New wheel speeds, at once (C5); the straight leg so far ends."""
        if (right_mm_s, left_mm_s) == (self.right.speed_mm_s, self.left.speed_mm_s):
            return
        self._end_leg()
        was_moving = self.moving
        self.right.speed_mm_s = right_mm_s
        self.left.speed_mm_s = left_mm_s
        if was_moving and right_mm_s == 0.0 and left_mm_s == 0.0:
            self.motions += 1
            self.rng = self._motion_rng()

    def _motion_rng(self) -> np.random.Generator:
        """The noise of one motion (rest to rest), keyed on the seed and its
        number: where the host stops a motion (a count or so later on a busy
        machine) changes that motion's last segment, never the noise of the
        motions after it, so a seed repeats its true poses."""
        return np.random.default_rng([self._motion_seed, self.motions])

    def stop(self) -> None:
        """Both wheels stop at once."""
        self.set_wheels(0.0, 0.0)

    def reset_encoders(self) -> None:
        """Reset: the counts go back to their origin (C3)."""
        self.left.counts = self.right.counts = self.encoder_origin
        self.left.fraction = self.right.fraction = 0.0

    # ---- time -------------------------------------------------------------------
    @property
    def moving(self) -> bool:
        """True while a wheel is commanded to turn (and not stalled)."""
        return any(w.speed_mm_s != 0.0 and not w.stalled for w in (self.left, self.right))

    def advance(self, t_end: float) -> None:
        """Run the physics to simulated time ``t_end`` s (one step: speeds are constant)."""
        dt = t_end - self.t
        if dt <= 0.0:
            return
        self.t = t_end
        travel = [0.0 if w.stalled else w.speed_mm_s * w.drag * dt for w in (self.left, self.right)]
        left_mm, right_mm = travel
        if left_mm == 0.0 and right_mm == 0.0:
            return
        k = self.geometry.metres_per_count * 1000.0
        self.left.turn(left_mm, k)
        self.right.turn(right_mm, k)
        base_mm = self.geometry.wheel_base_m * 1000.0
        self.distance_mm += 0.5 * (left_mm + right_mm)
        self.angle_deg += math.degrees((right_mm - left_mm) / base_mm)
        self.travel_m += 0.5 * (abs(left_mm) + abs(right_mm)) / 1000.0
        spin_rad = (right_mm - left_mm) / base_mm
        if spin_rad != 0.0:
            spin(self.true_x, self.true_y, self.true_theta, spin_rad, self.errors, self.rng)
        translation_m = 0.5 * (left_mm + right_mm) / 1000.0
        if translation_m != 0.0:
            self.leg_travel_m += translation_m
            self._drive_due(end_leg=False)

    def _drive_due(self, end_leg: bool) -> None:
        seg = self.segment_m
        due = int(abs(self.leg_travel_m) / seg)
        if due > self.leg_segments:
            self._drive(math.copysign(seg, self.leg_travel_m), due - self.leg_segments)
            self.leg_segments = due
        if end_leg:
            rest = abs(self.leg_travel_m) - self.leg_segments * seg
            if rest > NEGLIGIBLE_REST_M:
                self._drive(math.copysign(rest, self.leg_travel_m), 1)
            self.leg_travel_m = 0.0
            self.leg_segments = 0

    def _end_leg(self) -> None:
        self._drive_due(end_leg=True)

    def _drive(self, signed_segment_m: float, n: int) -> None:
        drive_straight(
            self.true_x, self.true_y, self.true_theta, signed_segment_m, n, self.params, self.rng
        )

    # ---- readings -----------------------------------------------------------------
    def encoder_counts(self) -> tuple[int, int]:
        """Left and right counts as the OI sends them: mod 65536, as s16 (C2)."""
        out = []
        for wheel in (self.left, self.right):
            value = wheel.counts % COUNTS_MODULUS
            out.append(value - COUNTS_MODULUS if value > 0x7FFF else value)
        return out[0], out[1]

    def take_distance(self) -> int:
        """Packet 19 since it was last read, mm, the remainder carried (C11)."""
        distance = max(-32768, min(32767, math.trunc(self.distance_mm)))
        self.distance_mm -= distance
        return distance

    def take_angle(self, angle_factor: float) -> int:
        """Packet 20 since it was last read, degrees times ``angle_factor``
        (1, or the old firmware's bug), the remainder carried (C11)."""
        angle = max(-32768, min(32767, math.trunc(self.angle_deg * angle_factor)))
        self.angle_deg -= angle / angle_factor
        return angle

    def true_pose(self) -> tuple[float, float, float]:
        """True pose: x m, y m, heading rad (unwrapped) in the start frame.

        Within a leg the segments are driven as the encoders reach them, so
        the true pose lags the encoders by less than one segment.
        """
        return float(self.true_x[0]), float(self.true_y[0]), float(self.true_theta[0])
