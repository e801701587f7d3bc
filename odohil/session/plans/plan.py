"""A calibration plan: which designs (forth-and-back, or general paths), how
many trials of each.

Text syntax (``--plan``): designs separated by ``;``, each a comma-separated
list of ``key=value``::

    k=1,l=6,n=30;k=20,l=0.5,n=30,variant=reverse;path=square:1.0,cw,n=10

- ``k``: forth-and-back pairs, a multiple of 1/2 (``k=0.5`` is one straight run);
- ``l``: leg length, metres;
- ``n``: number of trials of this design, a positive integer;
- ``variant`` (optional): ``turn`` (default, 180 degree turn at each end; the
  caller may default to ``reverse``, see :func:`parse_plan`) or
  ``reverse`` (drive back without turning).

Trials are numbered 1, 2, ... in plan order: the n trials of the first design,
then those of the second, and so on. Each trial's direction (forwards, or every
leg reversed) follows :func:`odohil.science.paths.floor_choreography`, so that
one-way trials come back over the same floor; journals written before this
(plans without ``"alternate"``) were driven forwards and are read so. A
general path is closed (it starts and ends at the same place, facing the same
way): it leaves the line's choreography where it found it, and needs the floor
of its bounding box (:func:`path_floor_m`) around its start.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import cached_property
from typing import Any

from odohil import units
from odohil.errors import ParameterError
from odohil.science.limits import RANGES
from odohil.science.path_designs import PathDesign, parse_path_design
from odohil.science.paths import VARIANTS, Design, FloorChoreography, floor_choreography
from odohil.session.robots.registry import check_leg

_KEYS = ("k", "l", "n", "variant", "path")

TrialShape = Design | PathDesign
"""What one trial of a plan drives: a forth-and-back design or a general path."""


def driven_backward(design: TrialShape) -> bool:
    """Whether a trial of ``design`` (as driven) runs every leg reversed (a
    general path: never)."""
    return isinstance(design, Design) and design.backward


def path_floor_m(design: PathDesign) -> tuple[float, float]:
    """The bounding box (along, across the start heading) of one trial of a
    closed path as the encoders drive it, metres: the floor it needs around
    its start mark."""
    x, y = 0.0, 0.0
    xs, ys = [0.0], [0.0]
    legs = design.path().legs
    for heading, sign, length in zip(legs.heading_rad, legs.sign, legs.length_m, strict=True):
        x += float(sign * length * math.cos(heading))
        y += float(sign * length * math.sin(heading))
        xs.append(x)
        ys.append(y)
    return (max(xs) - min(xs), max(ys) - min(ys))


@dataclass(frozen=True)
class PlanItem:
    """One design and how many trials of it.

    Attributes:
        design: the forth-and-back design (k, l metres, variant) or the
            general path (:class:`~odohil.science.path_designs.PathDesign`).
        n_trials: number of trials, at least 1.
    """

    design: TrialShape
    n_trials: int

    def __post_init__(self) -> None:
        if isinstance(self.n_trials, bool) or self.n_trials < 1:
            raise ParameterError(f"n must be a positive number of trials, got {self.n_trials!r}")

    def to_text(self) -> str:
        """This item in the ``--plan`` syntax."""
        d = self.design
        if isinstance(d, PathDesign):
            return f"path={d.to_text()},n={self.n_trials}"
        return f"k={d.k:g},l={d.l_m:g},n={self.n_trials},variant={d.variant}"

    def to_json(self) -> dict[str, Any]:
        """The plan record's entry: ``{"k", "l_m", "variant", "n"}`` or ``{"path", "n"}``."""
        d = self.design
        if isinstance(d, PathDesign):
            return {"path": d.to_text(), "n": self.n_trials}
        return {"k": d.k, "l_m": d.l_m, "variant": d.variant, "n": self.n_trials}


@dataclass(frozen=True)
class Plan:
    """The designs of a session, in order.

    Attributes:
        items: the designs and their trial counts.
        alternate: trials' directions follow :attr:`choreography` (False only
            for sessions journaled before directions alternated: all forwards).
    """

    items: tuple[PlanItem, ...]
    alternate: bool = True

    def __post_init__(self) -> None:
        if not self.items:
            raise ParameterError("a plan needs at least one design")

    @property
    def n_trials(self) -> int:
        """Total number of trials."""
        return sum(item.n_trials for item in self.items)

    @property
    def distance_m(self) -> float:
        """Total distance the plan drives, metres."""
        return sum(item.n_trials * item.design.distance_m for item in self.items)

    def design_index(self, trial: int) -> int:
        """The index of the design that trial number ``trial`` (1-based) runs."""
        if not 1 <= trial <= self.n_trials:
            raise ParameterError(f"trial {trial} is outside the plan's 1..{self.n_trials}")
        remaining = trial
        for index, item in enumerate(self.items):
            if remaining <= item.n_trials:
                return index
            remaining -= item.n_trials
        raise AssertionError("unreachable")

    def design_of(self, trial: int) -> TrialShape:
        """The design that trial number ``trial`` (1-based) runs, as driven
        (a forth-and-back design's ``backward`` set by the choreography; a
        general path as planned)."""
        item = self.items[self.design_index(trial)]
        if isinstance(item.design, PathDesign):
            return item.design
        return self.choreography.trial(self._line_number(trial))[0]

    def _line_number(self, trial: int) -> int:
        """Trial ``trial``'s number among the forth-and-back trials (the
        choreography's): closed paths leave the robot where they found it."""
        number, remaining = 0, trial
        for item in self.items:
            count = min(remaining, item.n_trials)
            if isinstance(item.design, Design):
                number += count
            remaining -= count
            if remaining <= 0:
                break
        return number

    @property
    def has_paths(self) -> bool:
        """Whether any design is a general path."""
        return any(isinstance(item.design, PathDesign) for item in self.items)

    @property
    def line_items(self) -> tuple[tuple[Design, int], ...]:
        """The forth-and-back designs and their trial counts, in order."""
        return tuple(
            (item.design, item.n_trials) for item in self.items if isinstance(item.design, Design)
        )

    @cached_property
    def choreography(self) -> FloorChoreography:
        """Each forth-and-back trial's direction and where it takes the robot
        on the floor (numbered among the forth-and-back trials only)."""
        return floor_choreography(self.line_items, alternate=self.alternate)

    @property
    def excursion_m(self) -> float:
        """Length of free floor the plan needs along the line of travel, metres
        (the forth-and-back trials'; a general path's, its bounding box's
        length along the start heading, when longer)."""
        line = self.choreography.excursion_m if self.line_items else 0.0
        boxes = [
            path_floor_m(item.design)[0]
            for item in self.items
            if isinstance(item.design, PathDesign)
        ]
        return max([line, *boxes])

    @property
    def width_m(self) -> float:
        """Width of free floor across the line of travel the plan's general
        paths need (their bounding boxes'), metres; 0 for forth-and-back only."""
        boxes = [
            path_floor_m(item.design)[1]
            for item in self.items
            if isinstance(item.design, PathDesign)
        ]
        return max([0.0, *boxes])

    def to_text(self) -> str:
        """The plan in the ``--plan`` syntax."""
        return ";".join(item.to_text() for item in self.items)

    def to_json(self) -> dict[str, Any]:
        """A JSON object: ``{"designs": [{"k", "l_m", "variant", "n"} or
        {"path", "n"}, ...]}``."""
        return {
            "designs": [item.to_json() for item in self.items],
            "alternate": self.alternate,
        }

    @classmethod
    def from_json(cls, raw: Mapping[str, Any]) -> Plan:
        """Inverse of :meth:`to_json`; ParameterError if malformed. Without
        ``"alternate"`` (older journals) every trial was driven forwards."""
        if not isinstance(raw, Mapping):
            raise ParameterError(f"a plan must be an object, got {raw!r}"[:300])
        designs = raw.get("designs")
        if not isinstance(designs, list):
            raise ParameterError("a plan object needs a list of designs")
        items = []
        for entry in designs:
            if not isinstance(entry, dict):
                raise ParameterError(f"a plan design must be an object, got {entry!r}")
            try:
                shape: TrialShape
                if "path" in entry:
                    if not isinstance(entry["path"], str):
                        raise TypeError("path must be text")
                    shape = parse_path_design(entry["path"])
                else:
                    shape = Design(float(entry["k"]), float(entry["l_m"]), entry["variant"])
                items.append(PlanItem(shape, int(entry["n"])))
            except (KeyError, TypeError, ValueError, OverflowError) as exc:
                if isinstance(exc, ParameterError):
                    raise
                raise ParameterError(f"malformed plan design {entry!r}: {exc}") from None
        alternate = raw.get("alternate", False)
        if not isinstance(alternate, bool):
            raise ParameterError(f"a plan's alternate must be true or false, got {alternate!r}")
        return cls(tuple(items), alternate=alternate)

    @classmethod
    def of(cls, designs: Sequence[tuple[TrialShape, int]]) -> Plan:
        """A plan from (design, n_trials) pairs, e.g. from the planner."""
        return cls(tuple(PlanItem(design, n) for design, n in designs))


def check_session_plan(plan: Plan, protocol: str | None) -> Plan:
    """``plan`` if a session can drive it on the robot of ``protocol``: every
    leg within the legs its backend drives (its facts' ``min_leg_m`` and
    ``max_leg_m``, odohil/session/robots/registry.py ``check_leg``; None, or a protocol
    with no installed backend: the science caps) and every design's trial
    count within ``RANGES["plan_n"]``; else ParameterError naming the design
    and the range.

    Made before any session is created or any port opened.
    """
    for number, item in enumerate(plan.items, start=1):
        try:
            design = item.design
            if isinstance(design, PathDesign):
                check_leg(protocol, design.side_m, "side")
            else:
                check_leg(protocol, design.l_m, "l")
            RANGES["plan_n"].check("n", item.n_trials)
        except ParameterError as exc:
            raise ParameterError(f"plan design {number} ({item.to_text()}): {exc}") from None
    total = RANGES["plan_n"]
    if plan.n_trials > total.high:
        raise ParameterError(
            f"the plan has {units.plural(plan.n_trials, 'trial')}; at most {total.high:g}"
        )
    return plan


def parse_plan(text: str, default_variant: str = "turn") -> Plan:
    """Parse the ``--plan`` syntax (see the module docstring); a design that
    names no variant gets ``default_variant``.

    Raises:
        ParameterError: the message names the design (1-based) and the problem.
    """
    parts = [part.strip() for part in text.split(";")]
    if not any(parts):
        raise ParameterError('empty plan; expected e.g. "k=1,l=6,n=30;k=20,l=0.5,n=30"')
    items = []
    for number, part in enumerate(parts, start=1):
        if not part:
            if number == len(parts):
                continue  # a trailing ';' is harmless
            raise ParameterError(f"plan design {number} is empty")
        try:
            items.append(_parse_item(part, default_variant))
        except ParameterError as exc:
            raise ParameterError(f"plan design {number} ({part!r}): {exc}") from None
    return Plan(tuple(items))


def _parse_item(text: str, default_variant: str) -> PlanItem:
    values: dict[str, str] = {}
    key = ""
    for field in text.split(","):
        name, sep, value = field.partition("=")
        if not sep and key == "path" and field.strip():
            values["path"] += "," + field.strip()  # the path's own commas
            continue
        key, value = name.strip().lower(), value.strip()
        if not sep or not key or not value:
            raise ParameterError(f"expected key=value, got {field.strip()!r}")
        if key not in _KEYS:
            raise ParameterError(f"unknown key {key!r}; keys are {', '.join(_KEYS)}")
        if key in values:
            raise ParameterError(f"{key} is given twice")
        values[key] = value
    if "path" in values:
        others = [k for k in ("k", "l", "variant") if k in values]
        if others:
            raise ParameterError(f"a path design takes path and n only, not {', '.join(others)}")
        if "n" not in values:
            raise ParameterError("missing n")
        return PlanItem(parse_path_design(values["path"]), _whole(values["n"]))
    missing = [key for key in ("k", "l", "n") if key not in values]
    if missing:
        raise ParameterError(f"missing {', '.join(missing)}")
    k = _number(values["k"], "k")
    l_m = _number(values["l"], "l")
    n = _whole(values["n"])
    variant = values.get("variant", default_variant).lower()
    if variant not in VARIANTS:
        raise ParameterError(f"variant must be one of {', '.join(VARIANTS)}, got {variant!r}")
    return PlanItem(Design(k, l_m, variant), n)


def _whole(text: str) -> int:
    try:
        return int(text)
    except ValueError:
        raise ParameterError(f"n must be a whole number, got {text!r}") from None


def _number(text: str, key: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise ParameterError(f"{key} must be a number, got {text!r}") from None
    if not math.isfinite(value):
        raise ParameterError(f"{key} must be finite, got {text!r}")
    return value
