"""The four odometry error parameters of Martinelli's model, in SI units."""

from __future__ import annotations

import math
from dataclasses import dataclass

from odohil import units
from odohil.errors import ParameterError

PARAMETER_NAMES = ("E_R", "E_T", "K_theta", "K_rho")
SI_UNITS = {"E_R": "rad/m", "E_T": "1", "K_theta": "rad^2/m", "K_rho": "m"}
PAPER_UNITS = {"E_R": "deg/m", "E_T": "1", "K_theta": "deg^2/m", "K_rho": "m"}
TURN_SI_UNITS = {"e_turn": "1", "K_spin": "rad^2/rad"}
"""A differential drive's turn errors (odohil/science/moments.py TurnErrors):
the turn-scale error (one per turn class: ``e_turn``, ``e_turn_spin``,
``e_turn_arc_cw``, ...) and the spins' heading variance per radian."""


def si_unit(name: str) -> str:
    """The SI unit of any parameter, the four and the turn errors."""
    if name in SI_UNITS:
        return SI_UNITS[name]
    return TURN_SI_UNITS[units.parameter_kind(name)]


@dataclass(frozen=True)
class ErrorParameters:
    """Systematic (E_R, E_T) and non-systematic (K_theta, K_rho) odometry error.

    Attributes (SI):
        e_r: systematic heading drift per metre driven, rad/m (eq. 2).
        e_t: systematic relative translation error, no unit; 1 + e_t scales
            every encoder distance (eq. 1).
        k_theta: heading variance per metre driven, rad^2/m (eq. 11).
        k_rho: translation variance per metre driven, m (eq. 14).
    """

    e_r: float
    e_t: float
    k_theta: float
    k_rho: float

    def __post_init__(self) -> None:
        for name, value in zip(PARAMETER_NAMES, self.as_tuple(), strict=True):
            if not math.isfinite(value):
                raise ParameterError(f"{name} must be a finite number, got {value!r}")
        if self.k_theta < 0:
            raise ParameterError(
                f"K_theta is a variance rate and cannot be negative: {self.k_theta}"
            )
        if self.k_rho < 0:
            raise ParameterError(f"K_rho is a variance rate and cannot be negative: {self.k_rho}")
        if self.e_t <= -1:
            raise ParameterError(f"1 + E_T must be positive, got E_T = {self.e_t}")

    @classmethod
    def from_paper_units(
        cls, e_r_deg_per_m: float, e_t: float, k_theta_deg2_per_m: float, k_rho_m: float
    ) -> ErrorParameters:
        """Build from the paper's units: deg/m, 1, deg^2/m, m."""
        return cls(
            e_r=units.deg_per_m_to_rad_per_m(e_r_deg_per_m),
            e_t=e_t,
            k_theta=units.deg2_per_m_to_rad2_per_m(k_theta_deg2_per_m),
            k_rho=k_rho_m,
        )

    def to_paper_units(self) -> dict[str, float]:
        """The four values in the paper's units (keys E_R, E_T, K_theta, K_rho)."""
        return {
            name: units.parameter_to_paper(name, value)
            for name, value in zip(PARAMETER_NAMES, self.as_tuple(), strict=True)
        }

    def to_si_dict(self) -> dict[str, float]:
        """The four values in SI (keys E_R, E_T, K_theta, K_rho)."""
        return dict(zip(PARAMETER_NAMES, self.as_tuple(), strict=True))

    def as_tuple(self) -> tuple[float, float, float, float]:
        """(e_r, e_t, k_theta, k_rho) in SI."""
        return (self.e_r, self.e_t, self.k_theta, self.k_rho)


NOMAD150 = ErrorParameters.from_paper_units(-0.202, -0.02, 0.012, 3.6e-5)
"""The paper's estimates for its Nomad 150 in an indoor hallway (section 5.2)."""
