"""Precision targets of the four parameters, in one place.

A parameter is known well enough when its standard error is at most

    max(fraction * |value|, floor)

with the fractions and floors below: 25 % of |E_R| (floor 0.005 deg/m),
25 % of |E_T| (floor 0.002: 2 mm per metre), 50 % of K_theta (floor
5e-7 rad^2/m) and 50 % of K_rho (floor 5e-6 m). The floors are what "near
zero" means for a value that may be zero. The planner uses them (at the prior
values) as the default targets of ``odohil plan``, the sufficiency check of
an estimate (at the estimated values) as its targets, so that a plan that
meets them leads, in expectation, to an estimate that has enough trials.
"""

from __future__ import annotations

from odohil import units
from odohil.science.parameters import PARAMETER_NAMES, ErrorParameters

TARGET_FRACTIONS: dict[str, float] = {"E_R": 0.25, "E_T": 0.25, "K_theta": 0.5, "K_rho": 0.5}
"""Largest standard error as a fraction of |value|, per parameter."""
TARGET_FLOORS: dict[str, float] = {
    "E_R": units.deg_per_m_to_rad_per_m(0.005),
    "E_T": 0.002,
    "K_theta": 5e-7,
    "K_rho": 5e-6,
}
"""Standard error always accepted (SI), per parameter: the value may be zero."""


def default_targets(values: ErrorParameters) -> dict[str, float]:
    """The target standard error (SI) of each parameter at ``values``."""
    return {
        name: max(TARGET_FRACTIONS[name] * abs(value), TARGET_FLOORS[name])
        for name, value in zip(PARAMETER_NAMES, values.as_tuple(), strict=True)
    }
