"""The overall time limit of one leg or one turn, from its length and speed (every backend).

A leg of ``d`` metres at ``v`` m/s with acceleration ``a`` m/s^2 takes, on a
trapezoidal speed profile, ``d / v + v / a`` when it reaches ``v`` and
``2 * sqrt(d / a)`` when it does not (a turn: the same in radians). The limit
is :data:`LIMIT_FACTOR` times that, plus :data:`LIMIT_MARGIN_S` for the slow
approach, the stop, the settling and a busy host; never more than the
settings' ``step_timeout_s``. A backend whose step is not done by then stops
the robot, confirms the stop and raises OdohilTimeoutError naming the step and
its limit: a leg that cannot end (encoders misread, a wheel that creeps) ends
there, not with the robot kilometres away.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from odohil.errors import ParameterError

LIMIT_FACTOR = 2.0
"""The limit is this many times the step's profile time, ..."""
LIMIT_MARGIN_S = 3.0
"""...plus this many seconds (slow approach, stop, settling, a busy host)."""


def profile_time_s(distance: float, speed: float, acceleration: float) -> float:
    """Time of a trapezoidal (or triangular) speed profile over ``distance``, s.

    Args:
        distance: metres (a leg) or radians (a turn); its magnitude is used.
        speed: the commanded speed, m/s or rad/s (> 0).
        acceleration: m/s^2 or rad/s^2 (> 0; infinite: speed at once).

    Raises:
        ParameterError: a speed or acceleration that is not positive, or a
            distance that is not finite.
    """
    if not (math.isfinite(distance) and math.isfinite(speed) and speed > 0 and acceleration > 0):
        raise ParameterError(
            f"a step needs a finite distance and a positive speed and acceleration; got "
            f"distance {distance!r}, speed {speed!r}, acceleration {acceleration!r}"
        )
    length = abs(distance)
    if math.isinf(acceleration):
        return length / speed
    if length >= speed * speed / acceleration:
        return length / speed + speed / acceleration
    return 2.0 * math.sqrt(length / acceleration)


@dataclass(frozen=True)
class StepLimit:
    """The time limit of one step, with the figures it came from (for messages).

    Attributes:
        what: the step (``leg 1 m``, ``turn 3.14 rad``).
        limit_s: the limit, s.
        profile_s: the speed profile's time, s.
        capped: True when ``step_timeout_s`` set the limit.
    """

    what: str
    limit_s: float
    profile_s: float
    capped: bool

    def expired_text(self) -> str:
        """Why the step was ended, for the error message."""
        why = (
            "the settings' step timeout"
            if self.capped
            else f"{LIMIT_FACTOR:g} x its {self.profile_s:.2f} s at the commanded speed "
            f"+ {LIMIT_MARGIN_S:g} s"
        )
        return f"{self.what} not done within its time limit of {self.limit_s:.1f} s ({why})"


def step_limit(
    what: str, distance: float, speed: float, acceleration: float, step_timeout_s: float
) -> StepLimit:
    """The time limit of one leg (metres, m/s, m/s^2) or turn (rad, rad/s, rad/s^2),
    at most ``step_timeout_s`` (see the module docstring)."""
    if not (math.isfinite(step_timeout_s) and step_timeout_s > 0):
        raise ParameterError(f"step_timeout_s must be positive, got {step_timeout_s!r}")
    profile = profile_time_s(distance, speed, acceleration)
    derived = LIMIT_FACTOR * profile + LIMIT_MARGIN_S
    return StepLimit(
        what=what,
        limit_s=min(derived, step_timeout_s),
        profile_s=profile,
        capped=step_timeout_s < derived,
    )
