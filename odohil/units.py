"""Every unit conversion odohil makes, in one place.

Inside odohil everything is SI: metres, radians, seconds. Two other unit
systems exist only at the edges:

- the paper's: E_R in deg/m, K_theta in deg^2/m (E_T and K_rho are already SI);
- the Nomad wire's: lengths in 0.1 inch, angles in 0.1 degree (and their
  per-second and per-second-squared rates).
"""

from __future__ import annotations

import math

METRES_PER_INCH = 0.0254
METRES_PER_WIRE_LENGTH = METRES_PER_INCH / 10.0
"""One wire length unit, 0.1 inch, in metres (2.54 mm)."""
RADIANS_PER_WIRE_ANGLE = math.radians(0.1)
"""One wire angle unit, 0.1 degree, in radians."""
WIRE_ANGLES_PER_TURN = 3600


def deg_per_m_to_rad_per_m(value: float) -> float:
    """E_R: deg/m (paper) to rad/m (SI)."""
    return math.radians(value)


def rad_per_m_to_deg_per_m(value: float) -> float:
    """E_R: rad/m (SI) to deg/m (paper)."""
    return math.degrees(value)


def deg2_per_m_to_rad2_per_m(value: float) -> float:
    """K_theta: deg^2/m (paper) to rad^2/m (SI)."""
    return value * (math.pi / 180.0) ** 2


def rad2_per_m_to_deg2_per_m(value: float) -> float:
    """K_theta: rad^2/m (SI) to deg^2/m (paper)."""
    return value * (180.0 / math.pi) ** 2


def radians_to_degrees(angle_rad: float) -> float:
    """An angle (e.g. phi1) from radians to degrees."""
    return math.degrees(angle_rad)


def rad2_to_deg2(value: float) -> float:
    """A squared angle (e.g. the variance phi2) from rad^2 to deg^2."""
    return value * (180.0 / math.pi) ** 2


def metres_to_wire(length_m: float) -> int:
    """A length in metres to the nearest whole number of wire units (0.1 inch)."""
    return round(length_m / METRES_PER_WIRE_LENGTH)


def wire_to_metres(length_wire: float) -> float:
    """A length in wire units (0.1 inch) to metres."""
    return length_wire * METRES_PER_WIRE_LENGTH


def radians_to_wire(angle_rad: float) -> int:
    """An angle in radians to the nearest whole number of wire units (0.1 degree)."""
    return round(angle_rad / RADIANS_PER_WIRE_ANGLE)


def wire_to_radians(angle_wire: float) -> float:
    """An angle in wire units (0.1 degree) to radians."""
    return angle_wire * RADIANS_PER_WIRE_ANGLE


def wrap_angle(angle_rad: float) -> float:
    """An angle reduced to (-pi, pi], in radians."""
    wrapped = math.remainder(angle_rad, 2.0 * math.pi)
    return math.pi if wrapped == -math.pi else wrapped
