"""What a relative move (``pr``) can express on the wire, in metres.

A ``pr`` carries its translation as an s16 in 0.1 inch, so a leg is realised
in whole wire units of 2.54 mm and cannot exceed 32767 of them (83.2 m). A leg
shorter than :data:`MIN_LEG_M` is refused: it would be sent as ``pr(0)`` or
nearly (the robot does not move, yet the trial looks valid), its rounding
error would be a large part of it, and the driver's end-of-step check (2 wire
units) could not tell it from no motion at all. The driver calls
:func:`check_leg_length_m` for every leg before it sends anything
(odohil/driver/nomad/motion.py); plan validation checks the same range
earlier, through the backend's facts (odohil/driver/nomad/facts.py).
"""

from __future__ import annotations

import math

from odohil.errors import ParameterError
from odohil.protocol.nomad.numbers import S16_MAX
from odohil.protocol.nomad.wire_units import METRES_PER_WIRE_LENGTH

WIRE_LENGTH_M = METRES_PER_WIRE_LENGTH
"""Resolution of a length on the wire: 0.1 inch = 2.54 mm, in metres."""
MAX_LEG_WIRE = S16_MAX
"""Largest |leg| one ``pr`` can carry, wire units (s16)."""
MAX_LEG_M = MAX_LEG_WIRE * WIRE_LENGTH_M
"""Largest |leg| one ``pr`` can carry, m (83.23 m)."""
MIN_LEG_M = 0.05
"""Smallest |leg| odohil drives, m: about 20 wire units, so that the wire's
2.54 mm resolution is at most 5 % of the leg and a robot that does not move
fails the 2-unit end-of-step check by a wide margin (the one minimum leg of
the Nomad: the driver's and the plan's)."""


def leg_to_wire(length_m: float) -> int:
    """A leg length (m, signed) as the ``pr`` translation that realises it, wire
    units; ParameterError (naming the accepted range) unless
    :data:`MIN_LEG_M` <= |leg| and |leg| <= :data:`MAX_LEG_M` after rounding to whole
    wire units, or if it is not finite."""
    if not math.isfinite(length_m):
        raise ParameterError(f"leg length must be a finite number of metres, got {length_m!r}")
    wire = round(length_m / WIRE_LENGTH_M)
    if abs(length_m) < MIN_LEG_M or abs(wire) > MAX_LEG_WIRE:
        raise ParameterError(
            f"leg length {length_m:g} m is {wire} wire units of 0.1 inch; |leg| must be "
            f"{MIN_LEG_M * 1000:.1f} mm to {MAX_LEG_M:.2f} m "
            f"(at most {MAX_LEG_WIRE} wire units)"
        )
    return wire


def check_leg_length_m(length_m: float) -> None:
    """ParameterError unless a leg of ``length_m`` metres (signed) can be driven
    by one ``pr``: see :func:`leg_to_wire`."""
    leg_to_wire(length_m)
