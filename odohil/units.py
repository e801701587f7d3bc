"""Every unit conversion odohil makes, and its one angle-wrapping convention.

Inside odohil everything is SI: metres, radians, seconds. Two other unit
systems exist only at the edges:

- the paper's: E_R in deg/m, K_theta in deg^2/m (E_T and K_rho are already SI);
  :func:`parameter_to_paper` and :func:`parameter_from_paper` convert one
  parameter's value or standard error by its name;
- a robot's wire units, which belong to its protocol (the Nomad's 0.1 inch
  and 0.1 degree: odohil/protocol/nomad/wire_units.py).

Angles. A heading, or a difference of headings, is reduced to (-pi, pi]
radians by :func:`wrap_angle` (a float) and :func:`wrap_angles` (an array),
both exact (``fmod`` by the float 2 pi, then one exact shift). To compare
headings known only modulo 2 pi with a reference (a model mean, a group's
circular mean), :func:`angle_near` moves them to within pi of it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any, Literal, overload

import numpy as np
import numpy.typing as npt

METRES_PER_INCH = 0.0254
"""One inch in metres."""


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


METRES_PER_LENGTH_UNIT = {"m": 1.0, "cm": 0.01, "mm": 0.001}
"""The length units an operator may type after a distance."""


def to_metres(length: float, unit: str) -> float:
    """A length typed in ``unit`` (m, cm or mm) in metres; metres are returned
    unchanged (the same float)."""
    return length if unit == "m" else length * METRES_PER_LENGTH_UNIT[unit]


def parameter_kind(name: str) -> str:
    """The kind of a parameter name: ``e_turn`` for every turn-scale error
    (``e_turn``, ``e_turn_spin``, ``e_turn_arc_cw``, ...), the name itself otherwise."""
    return "e_turn" if name.startswith("e_turn") else name


def parameter_to_paper(name: str, value_si: float) -> float:
    """A value (or standard error) of parameter ``name`` (E_R, E_T, K_theta,
    K_rho, e_turn..., K_spin) from SI to the paper's units: E_R rad/m to
    deg/m, K_theta rad^2/m to deg^2/m, K_spin rad^2/rad to deg^2/deg; E_T,
    K_rho and e_turn unchanged."""
    if name == "E_R":
        return rad_per_m_to_deg_per_m(value_si)
    if name == "K_theta":
        return rad2_per_m_to_deg2_per_m(value_si)
    if name == "K_spin":
        return math.degrees(value_si)
    return value_si


def parameter_from_paper(name: str, value_paper: float) -> float:
    """A value (or standard error) of parameter ``name`` from the paper's
    units to SI (the inverse of :func:`parameter_to_paper`)."""
    if name == "E_R":
        return deg_per_m_to_rad_per_m(value_paper)
    if name == "K_theta":
        return deg2_per_m_to_rad2_per_m(value_paper)
    if name == "K_spin":
        return math.radians(value_paper)
    return value_paper


UnitSystem = Literal["paper", "si"]
"""How parameters are shown to people: ``paper`` (E_R deg/m, K_theta deg^2/m)
or ``si`` (rad/m, rad^2/m); E_T (no unit) and K_rho (m) are the same in both.
JSON is always SI."""
UNIT_SYSTEMS: tuple[UnitSystem, ...] = ("paper", "si")
DEFAULT_UNIT_SYSTEM: UnitSystem = "paper"
"""The one default of every command that prints parameters for people."""

PARAMETER_UNIT_LABELS: dict[UnitSystem, dict[str, str]] = {
    "paper": {
        "E_R": "deg/m",
        "E_T": "",
        "K_theta": "deg^2/m",
        "K_rho": "m",
        "e_turn": "",
        "K_spin": "deg^2/deg",
    },
    "si": {
        "E_R": "rad/m",
        "E_T": "",
        "K_theta": "rad^2/m",
        "K_rho": "m",
        "e_turn": "",
        "K_spin": "rad^2/rad",
    },
}
"""Each parameter's unit as people read it; E_T and e_turn are plain numbers
(no unit: empty). Keys are parameter kinds (:func:`parameter_kind`)."""
NO_UNIT = "(no unit)"
"""What a unit column says for a plain number such as E_T."""


def parameter_in(name: str, value_si: float, system: UnitSystem) -> float:
    """A value (or standard error) of parameter ``name`` from SI to ``system``."""
    return parameter_to_paper(name, value_si) if system == "paper" else value_si


def parameter_unit(name: str, system: UnitSystem) -> str:
    """The unit of parameter ``name`` in ``system`` ("" for E_T, a plain number)."""
    return PARAMETER_UNIT_LABELS[system][parameter_kind(name)]


def unit_column(name: str, system: UnitSystem) -> str:
    """The unit of parameter ``name`` for a table's unit column: "(no unit)" for E_T."""
    return parameter_unit(name, system) or NO_UNIT


def with_unit(number_text: str, unit: str) -> str:
    """``"0.5 deg/m"``, or the number alone when there is no unit."""
    return f"{number_text} {unit}" if unit else number_text


def paper_text(name: str, value_si: float) -> str:
    """A value (or standard error) of parameter ``name`` as text in the paper's
    units, 3 significant digits: ``"0.1 deg/m"``; E_T and turn-scale errors
    (plain ratios) as percentages, ``"0.19 %"``."""
    if name == "E_T" or parameter_kind(name) == "e_turn":
        return f"{100.0 * value_si:.3g} %"
    return with_unit(f"{parameter_to_paper(name, value_si):.3g}", parameter_unit(name, "paper"))


def product_unit(a: str, b: str) -> str:
    """The unit of a product of two quantities: ``m^2`` for m times m, ``m rad``."""
    if a == b:
        return f"{a}^2"
    return f"{a} {b}"


def plural(count: int, noun: str, plural_form: str | None = None) -> str:
    """``"1 trial"``, ``"2 trials"``, ``"0 trials"``: the count with its noun
    agreed (``plural_form`` for nouns that do not take an s)."""
    return f"{count} {noun if count == 1 else (plural_form or noun + 's')}"


def join_words(words: Sequence[str]) -> str:
    """``"a"``, ``"a and b"``, ``"a, b and c"``: words joined for a sentence."""
    if len(words) <= 1:
        return "".join(words)
    return ", ".join(words[:-1]) + " and " + words[-1]


def plural_noun(count: int, noun: str, plural_form: str | None = None) -> str:
    """The noun alone, agreed with ``count`` (``"trial remains"`` wording helpers)."""
    return noun if count == 1 else (plural_form or noun + "s")


TWO_PI = 2.0 * math.pi


def wrap_angle(angle_rad: float) -> float:
    """An angle reduced to (-pi, pi], in radians (exact: see the module docstring)."""
    wrapped = math.fmod(angle_rad, TWO_PI)
    if wrapped > math.pi:
        return wrapped - TWO_PI
    if wrapped <= -math.pi:
        return wrapped + TWO_PI
    return wrapped


FloatArray = npt.NDArray[np.float64]


def wrap_angles(angles_rad: npt.ArrayLike) -> FloatArray:
    """Angles reduced to (-pi, pi], radians, element by element; the same
    values as :func:`wrap_angle` gives one by one."""
    wrapped = np.fmod(np.asarray(angles_rad, dtype=np.float64), TWO_PI)
    wrapped = np.where(wrapped > math.pi, wrapped - TWO_PI, wrapped)
    result: FloatArray = np.where(wrapped <= -math.pi, wrapped + TWO_PI, wrapped)
    return result


@overload
def angle_near(angle_rad: float, reference_rad: float) -> float: ...
@overload
def angle_near(angle_rad: FloatArray, reference_rad: float) -> FloatArray: ...
def angle_near(angle_rad: float | FloatArray, reference_rad: float) -> Any:
    """The angle(s) plus the multiple of 2 pi that puts them in
    (reference - pi, reference + pi], radians: headings known modulo 2 pi
    made comparable with a reference heading."""
    if isinstance(angle_rad, np.ndarray):
        return reference_rad + wrap_angles(angle_rad - reference_rad)
    return reference_rad + wrap_angle(float(angle_rad) - reference_rad)


def circular_mean(angles_rad: npt.ArrayLike) -> float:
    """The circular mean of angles (rad), in [-pi, pi]: the centre to put
    headings known modulo 2 pi near (:func:`angle_near`)."""
    angles = np.asarray(angles_rad, dtype=np.float64)
    return math.atan2(float(np.sin(angles).mean()), float(np.cos(angles).mean()))
