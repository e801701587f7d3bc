"""Documented caps on every number a user can give odohil, in one place.

Each range is inclusive, in the unit the user types (the paper's units at the
command line: deg/m, deg^2/m; metres; counts). The caps keep the work bounded:
the moments cost grows with the number of legs (2k) and with
(|E_R| + K_theta) times the distance driven, the planner's with the number of
trials, and the simulation's with trials x distance / segment.
See docs/limits.md. (Science layer, so every layer can use it.)
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from odohil import units
from odohil.errors import ParameterError

K_MAX = 500.0
"""Most forth-and-back pairs of one design (1000 legs)."""
L_MAX_M = 100.0
"""Longest leg of a design in the science commands, m."""
TRIAL_DISTANCE_MAX_M = 10_000.0
"""Most metres one trial drives (2kl, or a polygon's perimeter)."""


@dataclass(frozen=True)
class Range:
    """An inclusive range of one option, in the unit the user types.

    Attributes:
        low: smallest accepted value.
        high: largest accepted value.
        unit: the unit, for messages ("" for none).
        integer: whether only whole numbers make sense.
        half: whether the value must be a multiple of 1/2 (k).
    """

    low: float
    high: float
    unit: str = ""
    integer: bool = False
    half: bool = False

    def text(self) -> str:
        """The range as the messages give it, e.g. ``at least 0.5 and at most 500 pairs``."""
        unit = f" {self.unit}" if self.unit else ""
        kind = "a multiple of 1/2 " if self.half else ""
        return f"{kind}at least {self.low:g} and at most {self.high:g}{unit}"

    def check(self, name: str, value: float) -> float:
        """``value`` if finite and within the range, else a ParameterError naming ``name``."""
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise ParameterError(f"{name} must be a number, {self.text()}, got {value!r}")
        inside = math.isfinite(value) and self.low <= value <= self.high
        if inside and self.half:
            inside = abs(2.0 * value - round(2.0 * value)) <= 1e-9
        if not inside:
            raise ParameterError(f"{name} must be {self.text()}, got {value!r}")
        return value


RANGES: dict[str, Range] = {
    # designs
    "k": Range(0.5, K_MAX, "pairs", half=True),
    "l": Range(1e-3, L_MAX_M, "m"),
    "side": Range(1e-3, 1000.0, "m"),
    # error parameters, paper units (Nomad 150: -0.202, -0.02, 0.012, 3.6e-5)
    "E_R": Range(-90.0, 90.0, "deg/m"),
    "E_T": Range(-0.9, 0.9),
    "K_theta": Range(0.0, 1000.0, "deg^2/m"),
    "K_rho": Range(0.0, 1.0, "m"),
    # simulation
    "trials": Range(1, 1_000_000, "trials", integer=True),
    "n_simulate": Range(2, 1_000_000, "trials", integer=True),
    "segment_m": Range(1e-4, 10.0, "m"),
    "seed": Range(0, 2**63 - 1, integer=True),
    # planning
    "budget_m": Range(0.01, 100_000.0, "m"),
    "max_trials": Range(1, 10_000, "trials", integer=True),
    "max_designs": Range(1, 3, "designs", integer=True),
    "max_leg_m": Range(1e-3, L_MAX_M, "m"),
    "sigma_m": Range(1e-6, 1.0, "m"),
    "pose_sigma_m": Range(1e-6, 1.0, "m"),
    "pose_sigma_rad": Range(1e-6, 1.0, "rad"),
    "still_window_s": Range(0.02, 60.0, "s"),
    "screw_m": Range(-10.0, 10.0, "m"),
    "timeout_s": Range(1e-3, 600.0, "s"),
    "target_E_R": Range(1e-9, 100.0, "deg/m"),
    "target_E_T": Range(1e-12, 10.0),
    "target_K_theta": Range(1e-12, 100.0, "deg^2/m"),
    "target_K_rho": Range(1e-12, 10.0, "m"),
    "min_trials_per_design": Range(2, 1000, "trials", integer=True),
    "measure_s": Range(0.0, 3600.0, "s"),
    "budget_min": Range(0.1, 100_000.0, "min"),
    # driving speed (plan's time model, export's linearisation) and exports
    "speed": Range(0.01, 10.0, "m/s"),
    "rate_hz": Range(0.1, 1000.0, "Hz"),
    "update_min_d_m": Range(0.001, 10.0, "m"),
    "update_min_a_rad": Range(0.001, 3.14159, "rad"),
    # the link and the fake robot
    "baud": Range(50, 4_000_000, "bit/s", integer=True),
    "time_scale": Range(0.01, 1e6),
    # a session plan (its legs: the robot's own limits, RobotFacts.check_leg)
    "plan_n": Range(1, 10_000, "trials", integer=True),
}
"""Every numeric input's accepted range, by name (see docs/limits.md)."""

SIMULATION_SEGMENTS_MAX = 1e9
"""Most simulated segments (trials x segments per trial) one command runs
(about half a minute of work)."""


def check(name: str, value: float, label: str | None = None) -> float:
    """``value`` checked against ``RANGES[name]``; the message names ``label``
    (default ``name``). Raises ParameterError."""
    return RANGES[name].check(label or name, value)


def check_simulation_work(n_trials: int, segments_per_trial: float) -> None:
    """Refuse a simulation of more than :data:`SIMULATION_SEGMENTS_MAX` segments
    in all (ParameterError naming the trials and the segment length)."""
    total = float(n_trials) * float(segments_per_trial)
    if total > SIMULATION_SEGMENTS_MAX:
        raise ParameterError(
            f"{units.plural(n_trials, 'trial')} of {segments_per_trial:.0f} segments each is "
            f"{total:.3g} segments; at most {SIMULATION_SEGMENTS_MAX:.0e}: give fewer "
            "trials or a longer segment (--segment-m)"
        )


def segments_of(leg_lengths_m: list[float], segment_m: float) -> float:
    """Number of simulated segments of a path: each leg cut into pieces of at
    most ``segment_m`` metres."""
    return float(sum(max(1, math.ceil(length / segment_m - 1e-9)) for length in leg_lengths_m))
