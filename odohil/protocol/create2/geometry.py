"""The Create 2's nominal kinematic constants, from the Open Interface
specification (p.5, p.31; docs/create2.md)."""

from __future__ import annotations

from odohil.science.diff_drive import DiffDriveGeometry

COUNTS_PER_REV = 508.8
"""Encoder counts per wheel revolution (p.31)."""
WHEEL_DIAMETER_M = 0.072
"""Wheel diameter, m (p.31)."""
WHEEL_BASE_M = 0.235
"""Distance between the wheels, m (p.5)."""
CREATE2_GEOMETRY = DiffDriveGeometry(COUNTS_PER_REV, WHEEL_DIAMETER_M, WHEEL_BASE_M)
"""The three as a geometry: the default of a description's ``[robot]`` keys
(odohil/driver/create2/facts.py)."""
