"""General path designs: squares, regular polygons and polygonal circles.

A :class:`PathDesign` is to a general path what :class:`~odohil.science.paths.Design`
is to a forth-and-back run: a small value naming one trial, which a robot drives
(:meth:`PathDesign.path`) and a plan repeats. Text syntax (``--path``, and
``path=`` in a plan)::

    square:SIDE[,cw|ccw]            four legs of SIDE metres, 90 degree turns
    polygon:N,SIDE[,cw|ccw]         N legs of SIDE metres, 360/N degree turns
    circle:RADIUS,N[,cw|ccw]        a circle of RADIUS metres as N legs and turns

Counter-clockwise (``ccw``, turning left) is the default. Every one is closed:
the encoders say it ends where it started, facing the same way.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from typing import Literal

from odohil.errors import ParameterError
from odohil.science.limits import RANGES
from odohil.science.paths import EncoderPath, polygonal_circle, regular_polygon

PathKind = Literal["square", "polygon", "circle"]
PATH_KINDS: tuple[PathKind, ...] = ("square", "polygon", "circle")
PATH_DESIGN_SYNTAX = "square:SIDE[,cw|ccw], polygon:N,SIDE[,cw|ccw] or circle:RADIUS,N[,cw|ccw]"
_DIRECTIONS = {"ccw": True, "cw": False}


@dataclass(frozen=True)
class PathDesign:
    """One closed general path, driven as one trial.

    Attributes:
        kind: ``square``, ``polygon`` or ``circle``.
        n_sides: number of legs (4 for a square).
        size_m: the side (square, polygon) or the radius (circle), metres.
        counter_clockwise: turning left (True) or right.
    """

    kind: PathKind
    n_sides: int
    size_m: float
    counter_clockwise: bool = True

    def __post_init__(self) -> None:
        if self.kind not in PATH_KINDS:
            raise ParameterError(f"a path is one of {', '.join(PATH_KINDS)}, got {self.kind!r}")
        if self.kind == "square" and self.n_sides != 4:
            raise ParameterError(f"a square has 4 sides, got {self.n_sides!r}")
        self.path()  # every range checked once, here

    @property
    def direction(self) -> str:
        """``ccw`` or ``cw``."""
        return "ccw" if self.counter_clockwise else "cw"

    @property
    def side_m(self) -> float:
        """Length of each leg, metres."""
        if self.kind == "circle":
            return 2.0 * self.size_m * math.sin(math.pi / self.n_sides)
        return self.size_m

    @property
    def distance_m(self) -> float:
        """Distance driven by one trial, metres."""
        return self.n_sides * self.side_m

    def path(self) -> EncoderPath:
        """The encoder path of one trial."""
        if self.kind == "circle":
            return polygonal_circle(self.size_m, self.n_sides, self.counter_clockwise)
        return regular_polygon(self.n_sides, self.size_m, self.counter_clockwise, name=self.label())

    def to_text(self) -> str:
        """This design in the text syntax (module docstring), e.g. ``square:1,cw``."""
        if self.kind == "square":
            return f"square:{self.size_m:g},{self.direction}"
        if self.kind == "polygon":
            return f"polygon:{self.n_sides},{self.size_m:g},{self.direction}"
        return f"circle:{self.size_m:g},{self.n_sides},{self.direction}"

    def label(self) -> str:
        """A short human-readable name, e.g. ``square 1 m cw``."""
        if self.kind == "square":
            return f"square {self.size_m:g} m {self.direction}"
        if self.kind == "polygon":
            return f"polygon {self.n_sides}x{self.size_m:g} m {self.direction}"
        return f"circle r={self.size_m:g} m {self.n_sides} sides {self.direction}"

    def slug(self) -> str:
        """A folder name for it, e.g. ``square-1-cw``."""
        return re.sub(r"[^A-Za-z0-9.]+", "-", self.to_text()).strip("-")


def parse_path_design(text: str) -> PathDesign:
    """Parse the text syntax (module docstring).

    Raises:
        ParameterError: naming the part that is wrong and the accepted forms.
    """
    kind, _, rest = text.strip().partition(":")
    kind = kind.strip().lower()
    parts = [part.strip().lower() for part in rest.split(",")] if rest.strip() else []
    counter_clockwise = True
    if parts and parts[-1] in _DIRECTIONS:
        counter_clockwise = _DIRECTIONS[parts.pop()]
    try:
        if kind == "square":
            _count(parts, 1, "SIDE")
            return PathDesign("square", 4, _number(parts[0], "SIDE"), counter_clockwise)
        if kind == "polygon":
            _count(parts, 2, "N,SIDE")
            sides = _sides(parts[0])
            return PathDesign("polygon", sides, _number(parts[1], "SIDE"), counter_clockwise)
        if kind == "circle":
            _count(parts, 2, "RADIUS,N")
            radius = _number(parts[0], "RADIUS")
            RANGES["side"].check("RADIUS", radius)
            return PathDesign("circle", _sides(parts[1]), radius, counter_clockwise)
    except ParameterError as exc:
        raise ParameterError(f"{text.strip()!r}: {exc} (accepted: {PATH_DESIGN_SYNTAX})") from None
    raise ParameterError(f"{text.strip()!r}: unknown path; accepted: {PATH_DESIGN_SYNTAX}")


def _count(parts: list[str], n: int, names: str) -> None:
    if len(parts) != n:
        raise ParameterError(f"give {names}, then optionally cw or ccw")


def _number(text: str, name: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise ParameterError(f"{name} must be a number, got {text!r}") from None
    if not math.isfinite(value) or value <= 0:
        raise ParameterError(f"{name} must be a positive number of metres, got {text!r}")
    return value


def _sides(text: str) -> int:
    try:
        sides = int(text)
    except ValueError:
        raise ParameterError(f"N must be a whole number of sides, got {text!r}") from None
    if sides < 3:
        raise ParameterError(f"N must be at least 3 sides, got {sides}")
    return sides
