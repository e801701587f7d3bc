"""No robot constant outside odohil/protocol and odohil/driver (issue 18).

A robot's facts (line speeds, wire units, what one wire command can carry,
leg limits, counts per revolution) belong to its backend: the backend
declares them in its RobotFacts (odohil/driver/<robot>/) and every other
layer reads them through the registry (odohil/session/robots/registry.py). This scans
the code of every other package of odohil for the numeric literals and the
names those facts had before they moved. Robot description files
(odohil/robots/*.toml) are data and are not scanned.
"""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
ALLOWED = ("protocol", "driver")
"""The packages of odohil that own robot constants."""

ROBOT_NUMBERS: dict[float, str] = {
    # line speeds (the Nomad's 4800..38400, the Create 2's up to 115200)
    1200: "a baud rate",
    2400: "a baud rate",
    4800: "a baud rate",
    9600: "a baud rate",
    14400: "a baud rate",
    19200: "a baud rate",
    28800: "a baud rate",
    38400: "a baud rate",
    57600: "a baud rate",
    115200: "a baud rate",
    # the Nomad's wire unit (0.1 inch) and what one pr carries (s16)
    0.00254: "a wire unit (0.1 inch)",
    32767: "the s16 wire limit",
    83.2: "the longest leg one pr carries",
    83.228: "the longest leg one pr carries",
    # a differential drive's counts per revolution (the Create 2, the optiodom robot)
    508.8: "counts per revolution",
    2796.8: "counts per revolution",
    # the Create 2's wheel base (odohil/protocol/create2/geometry.py)
    0.235: "a wheel base",
}
"""Numeric literals that are a robot's constant, and what each is."""

ROBOT_NAMES = {
    "BAUD_RATES",
    "DEFAULT_BAUD",
    "PROTOCOL_BAUD_RATES",
    "EXACT_TURN_PROTOCOLS",
    "MAX_WIRE",
    "S16_WIRE_MAX",
    "WIRE_METRES_PER_UNIT",
    "WIRE_MAX_LEG_M",
    "METRES_PER_WIRE_LENGTH",
    "RADIANS_PER_WIRE_ANGLE",
    "WIRE_ANGLES_PER_TURN",
    "MIN_LEG_M",
    "MAX_LEG_M",
    "MIN_LEG_WIRE",
    "MAX_LEG_WIRE",
    "OPTIODOM_GEOMETRY",
    "NOMINAL_WHEEL_BASE_M",
    "WHEEL_BASE_M",
}
"""Names of robot constants (defined or used) that only protocol/ and driver/ may hold."""


def _scanned() -> list[Path]:
    package = ROOT / "odohil"
    return [
        path
        for path in sorted(package.rglob("*.py"))
        if path.relative_to(package).parts[0] not in ALLOWED
    ]


def _findings(path: Path) -> list[str]:
    tree = ast.parse(path.read_text(), filename=str(path))
    where = path.relative_to(ROOT)
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Constant) and not isinstance(node.value, bool | str | bytes):
            value = node.value
            if isinstance(value, int | float) and value in ROBOT_NUMBERS:
                found.append(f"{where}:{node.lineno}: {value!r} ({ROBOT_NUMBERS[value]})")
        name = None
        if isinstance(node, ast.Name):
            name = node.id
        elif isinstance(node, ast.Attribute):
            name = node.attr
        elif isinstance(node, ast.alias):
            name = node.asname or node.name.rsplit(".", 1)[-1]
        if name in ROBOT_NAMES:
            found.append(f"{where}:{getattr(node, 'lineno', 0)}: the name {name}")
    return found


def test_the_scan_sees_the_robot_constants_where_they_belong() -> None:
    """The scan is not blind: the backends' own modules hold what it looks for."""
    nomad = _findings(ROOT / "odohil" / "driver" / "nomad" / "link.py")
    create2 = _findings(ROOT / "odohil" / "protocol" / "create2" / "opcodes.py")
    assert any("38400" in f for f in nomad)
    assert any("115200" in f for f in create2)
    assert any("BAUD_RATES" in f for f in create2)
    geometry = _findings(ROOT / "odohil" / "protocol" / "create2" / "geometry.py")
    assert any("a wheel base" in f for f in geometry)


def test_no_robot_constant_outside_protocol_and_driver() -> None:
    offenders = [finding for path in _scanned() for finding in _findings(path)]
    assert offenders == []
