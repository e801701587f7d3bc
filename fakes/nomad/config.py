"""Settings of one fake robot."""

from __future__ import annotations

from dataclasses import dataclass

from fakes.nomad.faults import FaultSpec, parse_fault
from odohil.errors import ParameterError
from odohil.science.parameters import NOMAD150, ErrorParameters
from odohil.science.simulator import DEFAULT_SEGMENT_M


@dataclass(frozen=True)
class EmulatorConfig:
    """Everything that makes one fake robot behave as it does.

    Attributes:
        params: the odometry error parameters the true pose drifts by (SI).
        seed: seed of the noise generator (None: fresh entropy).
        time_scale: how many simulated seconds pass per wall second (motion,
            accelerations, ``zr`` and the robot timestamp); the watchdog and
            ``ws`` timeouts count wall seconds.
        faults: the faults to inject.
        segment_m: longest segment of the discrete error model, encoder metres.
        sonar_inches: the range every sonar reports, inches (0..255).
        voltage_raw: the raw CPU and motor voltage bytes (CHOICE C12).
        zr_seconds: shortest duration of ``zr``, simulated seconds (C10).
    """

    params: ErrorParameters = NOMAD150
    seed: int | None = None
    time_scale: float = 1.0
    faults: tuple[FaultSpec, ...] = ()
    segment_m: float = DEFAULT_SEGMENT_M
    sonar_inches: int = 255
    voltage_raw: tuple[int, int] = (230, 230)
    zr_seconds: float = 3.0

    def __post_init__(self) -> None:
        if not self.time_scale > 0:
            raise ParameterError(f"time_scale must be positive, got {self.time_scale}")
        if not self.segment_m > 0:
            raise ParameterError(f"segment_m must be positive, got {self.segment_m}")
        if not 0 <= self.sonar_inches <= 255:
            raise ParameterError(f"sonar range is one byte, got {self.sonar_inches}")
        if self.zr_seconds < 0:
            raise ParameterError(f"zr_seconds cannot be negative, got {self.zr_seconds}")


def build_config(
    *,
    seed: int | None = None,
    e_r_deg_per_m: float = NOMAD150.to_paper_units()["E_R"],
    e_t: float = NOMAD150.e_t,
    k_theta_deg2_per_m: float = NOMAD150.to_paper_units()["K_theta"],
    k_rho_m: float = NOMAD150.k_rho,
    time_scale: float = 1.0,
    faults: list[str] | tuple[str, ...] = (),
) -> EmulatorConfig:
    """An :class:`EmulatorConfig` from command-line style values (paper units, fault strings)."""
    params = ErrorParameters.from_paper_units(e_r_deg_per_m, e_t, k_theta_deg2_per_m, k_rho_m)
    return EmulatorConfig(
        params=params,
        seed=seed,
        time_scale=time_scale,
        faults=tuple(parse_fault(text) for text in faults),
    )
