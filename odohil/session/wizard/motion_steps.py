"""How far a forth-and-back motion has come, from its encoder samples: which
step (leg or turn) the robot is in and how much of it is covered. The wizard's
progress bar shows it; what it means is here."""

from __future__ import annotations

import math

from odohil import units
from odohil.driver.odometry import OdometrySample
from odohil.science.paths import Drivable, Leg, Turn

__all__ = [
    "MotionSteps",
    "pose_text",
]


def step_fraction(item: Leg | Turn, start: OdometrySample, sample: OdometrySample) -> float:
    """How much of the step ``item`` that began at ``start`` is covered at
    ``sample``: distance over the leg's length, or angle over the turn's (at
    most half a turn), 0 for a step of no size; not capped at 1."""
    if isinstance(item, Leg) and item.length_m > 0:
        moved = math.hypot(sample.x_m - start.x_m, sample.y_m - start.y_m)
        return moved / abs(item.length_m)
    if isinstance(item, Turn) and item.angle_rad != 0:
        turned = abs(units.wrap_angle(sample.theta_rad - start.theta_rad))
        return turned / min(abs(item.angle_rad), math.pi)
    return 0.0


class MotionSteps:
    """Follows one motion of a design, sample by sample. The first sample is
    taken before the first step; a step ends at the first sample that shows
    the robot at rest."""

    def __init__(self, design: Drivable) -> None:
        self.steps: tuple[Leg | Turn, ...] = design.path().steps
        self.step = 0
        self.start: OdometrySample | None = None

    def sample(self, sample: OdometrySample) -> float | None:
        """The steps covered so far, the current one by its fraction (at most
        1): ``2.5`` is half-way through the third step. None for the first
        sample and for samples after the last step."""
        if self.start is None:
            self.start = sample
            return None
        done = None
        if self.step < len(self.steps):
            done = self.step + min(1.0, step_fraction(self.steps[self.step], self.start, sample))
        if not sample.moving:
            self.step, self.start = self.step + 1, sample
        return done


def pose_text(sample: OdometrySample) -> str:
    """``x=+0.100 m y=-0.002 m heading=  12.0 deg``: an encoder sample for people."""
    return (
        f"x={sample.x_m:+.3f} m y={sample.y_m:+.3f} m "
        f"heading={math.degrees(sample.theta_rad):6.1f} deg"
    )
