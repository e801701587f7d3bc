"""The Nomad 150's wire units: lengths in 0.1 inch, angles in 0.1 degree
(and their per-second and per-second-squared rates).

The Nomad reports and accepts absolute angles as whole tenths of a degree in
[0, 3600) (:func:`wire_angle_in_turn`), because that is what its protocol
carries; a difference of two wire angles is reduced to (-1800, 1800]
(:func:`wire_angle_difference`), the convention of
:func:`odohil.units.wrap_angle`.
"""

from __future__ import annotations

import math

from odohil.units import METRES_PER_INCH

METRES_PER_WIRE_LENGTH = METRES_PER_INCH / 10.0
"""One wire length unit, 0.1 inch, in metres (2.54 mm)."""
RADIANS_PER_WIRE_ANGLE = math.radians(0.1)
"""One wire angle unit, 0.1 degree, in radians."""
WIRE_ANGLES_PER_TURN = 3600


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


def wire_angle_in_turn(angle_wire: int) -> int:
    """An absolute wire angle (0.1 degree) as the wire carries it, in [0, 3600)."""
    return angle_wire % WIRE_ANGLES_PER_TURN


def wire_angle_difference(a_wire: int, b_wire: int) -> int:
    """``a - b`` of two wire angles (0.1 degree), reduced to (-1800, 1800]."""
    d = (a_wire - b_wire) % WIRE_ANGLES_PER_TURN
    return d - WIRE_ANGLES_PER_TURN if d > WIRE_ANGLES_PER_TURN // 2 else d
