"""Encoder-measured paths: straight legs and in-place turns.

A path is what the encoders say the robot did. In Martinelli's model the error
grows with the distance driven only, so in-place turns are error free and every
leg is a straight run at constant encoder heading.

Reading of eq. (2) for legs driven backwards: the encoder distance of each
segment, delta-rho-bar, is signed (negative when reversing), so the systematic
terms E_T delta-rho-bar and E_R delta-rho-bar change sign with it; the
variances (eqs. 10-14) grow with the distance driven, |delta-rho-bar|. For the
``turn`` variant of the forth-and-back motion this is the paper's motion; for
``reverse`` it means the systematic heading drift of the way out is undone on
the way back.

Driving a whole path backwards (every leg's encoder distance negated, the turns
unchanged, see :attr:`Design.backward`) mirrors it: the turns are multiples of
pi, so each heading theta becomes 2 h - theta with 2 h a multiple of 2 pi, and
the pose change (x, y, theta) of the model is distributed as (-x, y, -theta) of
the forward path. One-way designs alternate between the two so that the robot
comes back over the same floor (see :func:`floor_choreography`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Literal, Protocol

import numpy as np
import numpy.typing as npt

from odohil.errors import ParameterError
from odohil.science.limits import RANGES, TRIAL_DISTANCE_MAX_M

Variant = Literal["turn", "reverse"]
VARIANTS: tuple[Variant, ...] = ("turn", "reverse")

FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True)
class Leg:
    """A straight run at constant encoder heading.

    Attributes:
        length_m: encoder distance in metres; negative drives backwards
            without turning.
    """

    length_m: float

    def __post_init__(self) -> None:
        if not math.isfinite(self.length_m) or self.length_m == 0.0:
            raise ParameterError(f"a leg needs a finite non-zero length, got {self.length_m!r} m")


TurnKind = Literal["spin", "arc"]
TURN_KINDS: tuple[TurnKind, ...] = ("spin", "arc")
TURN_CLASSES: tuple[str, ...] = ("spin ccw", "spin cw", "arc ccw", "arc cw")
"""The four classes of turns a turn-scale error may differ between: kind
(spin, arc) and direction (ccw: positive angle, cw: negative); the rows of
:class:`TurnTable`."""


@dataclass(frozen=True)
class Turn:
    """An in-place turn (no distance driven), counter-clockwise positive.

    Attributes:
        angle_rad: encoder heading change in radians.
        kind: ``"spin"`` for a turn in place (the wheels opposite), ``"arc"``
            for the heading change of a curve cut into short legs and turns;
            a differential drive's turn-scale error differs between the two
            (docs/recording.md), an exact-turn model ignores it.
    """

    angle_rad: float
    kind: TurnKind = "spin"

    def __post_init__(self) -> None:
        if not math.isfinite(self.angle_rad):
            raise ParameterError(f"a turn needs a finite angle, got {self.angle_rad!r} rad")


Step = Leg | Turn


@dataclass(frozen=True)
class LegTable:
    """The legs of a path as arrays, one entry per leg (turns folded in).

    Attributes:
        heading_rad: encoder heading during the leg, relative to the start.
        sign: +1 driving forwards, -1 reversing.
        length_m: distance driven, |encoder distance|, metres.
        start_arc_m: distance driven before the leg starts, metres.
        start_signed_m: signed encoder distance before the leg starts, metres
            (what E_R multiplies).
    """

    heading_rad: FloatArray
    sign: FloatArray
    length_m: FloatArray
    start_arc_m: FloatArray
    start_signed_m: FloatArray


@dataclass(frozen=True)
class TurnTable:
    """The turns of a path by class (:data:`TURN_CLASSES`), for turn-error models.

    Attributes:
        before_rad: (4, n_legs) per class, the sum of the encoder angles
            (signed, rad) of that class's turns before each leg.
        total_rad: (4,) per class, the sum over the whole path.
        spin_before_rad: (n_legs,) sum of |angle| of the spins before each leg, rad.
        spin_total_rad: sum of |angle| of every spin, rad.
    """

    before_rad: FloatArray
    total_rad: FloatArray
    spin_before_rad: FloatArray
    spin_total_rad: float

    @property
    def total_abs_rad(self) -> FloatArray:
        """(4,) per class, the sum of |angle| over the path, rad."""
        out: FloatArray = np.abs(self.total_rad)
        return out


def turn_class_index(turn: Turn) -> int:
    """The row of :data:`TURN_CLASSES` a (non-zero) turn belongs to."""
    return (0 if turn.kind == "spin" else 2) + (0 if turn.angle_rad > 0 else 1)


@dataclass(frozen=True)
class EncoderPath:
    """A sequence of legs and in-place turns, as measured by the encoders."""

    steps: tuple[Step, ...]
    name: str = ""
    _legs: LegTable = field(init=False, repr=False, compare=False)
    _turns: TurnTable = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if not any(isinstance(step, Leg) for step in self.steps):
            raise ParameterError("a path needs at least one leg")
        heading, arc, signed = 0.0, 0.0, 0.0
        rows: list[tuple[float, float, float, float, float]] = []
        by_class, spun = np.zeros(4), 0.0
        before: list[FloatArray] = []
        spin_before: list[float] = []
        for step in self.steps:
            if isinstance(step, Turn):
                heading += step.angle_rad
                if step.angle_rad != 0.0:
                    by_class[turn_class_index(step)] += step.angle_rad
                    if step.kind == "spin":
                        spun += abs(step.angle_rad)
                continue
            before.append(by_class.copy())
            spin_before.append(spun)
            sign = 1.0 if step.length_m > 0 else -1.0
            rows.append((heading, sign, abs(step.length_m), arc, signed))
            arc += abs(step.length_m)
            signed += step.length_m
        table = np.array(rows, dtype=np.float64)
        legs = LegTable(
            heading_rad=table[:, 0].copy(),
            sign=table[:, 1].copy(),
            length_m=table[:, 2].copy(),
            start_arc_m=table[:, 3].copy(),
            start_signed_m=table[:, 4].copy(),
        )
        object.__setattr__(self, "_legs", legs)
        turns = TurnTable(
            before_rad=np.array(before, dtype=np.float64).T.copy(),
            total_rad=by_class,
            spin_before_rad=np.array(spin_before, dtype=np.float64),
            spin_total_rad=spun,
        )
        object.__setattr__(self, "_turns", turns)

    @property
    def legs(self) -> LegTable:
        """The legs as arrays (see :class:`LegTable`)."""
        return self._legs

    @property
    def turns(self) -> TurnTable:
        """The turns by class (see :class:`TurnTable`)."""
        return self._turns

    @property
    def distance_m(self) -> float:
        """Total distance driven, rho-bar, metres."""
        return float(self._legs.length_m.sum())

    @property
    def signed_distance_m(self) -> float:
        """Sum of signed encoder distances, metres (what E_R multiplies in total)."""
        return float((self._legs.sign * self._legs.length_m).sum())

    @property
    def net_turn_rad(self) -> float:
        """Sum of the in-place turns, radians, not reduced modulo 2 pi."""
        return float(sum(step.angle_rad for step in self.steps if isinstance(step, Turn)))

    @property
    def winding_rad(self) -> float:
        """The multiple of 2 pi nearest to the net turn, radians.

        Pose changes report the heading change minus this, so that a closed
        path's heading change is near zero rather than near 2 pi m.
        """
        return 2.0 * math.pi * round(self.net_turn_rad / (2.0 * math.pi))

    def encoder_end_pose(self) -> tuple[float, float, float]:
        """Where the encoders say the path ends: (x m, y m, theta rad), theta
        relative to the start and reduced by :attr:`winding_rad`."""
        legs = self._legs
        x = float((legs.sign * legs.length_m * np.cos(legs.heading_rad)).sum())
        y = float((legs.sign * legs.length_m * np.sin(legs.heading_rad)).sum())
        return (x, y, self.net_turn_rad - self.winding_rad)


def check_trial_length(label: str, path: EncoderPath) -> None:
    """ParameterError when one trial of ``path`` drives more than
    :data:`~odohil.science.limits.TRIAL_DISTANCE_MAX_M` metres, the longest trial
    any design may drive: a robot backend calls it before it sends anything."""
    if path.distance_m > TRIAL_DISTANCE_MAX_M:
        raise ParameterError(
            f"{label} drives {path.distance_m:g} m in one trial; at most "
            f"{TRIAL_DISTANCE_MAX_M:g} m (odohil/science/limits.py); nothing sent"
        )


class Drivable(Protocol):
    """What a robot can drive as one trial: a forth-and-back :class:`Design`
    or a general path design (odohil/science/path_designs.py)."""

    def path(self) -> EncoderPath:
        """The encoder path of one trial."""
        ...

    def label(self) -> str:
        """A short human-readable name."""
        ...


def _leg_count(k: float) -> int:
    legs = 2.0 * k
    if not math.isfinite(legs) or legs < 1 or abs(legs - round(legs)) > 1e-9:
        raise ParameterError(f"k must be a positive multiple of 1/2, got {k!r}")
    return round(legs)


@dataclass(frozen=True)
class Design:
    """One forth-and-back experiment design: 2k legs of length l.

    Attributes:
        k: number of forth-and-back pairs; a multiple of 1/2 (k = 1/2 is a
            one-way run).
        l_m: leg length in metres.
        variant: ``turn`` (180 degree turn in place at each end) or
            ``reverse`` (drive back without turning).
        backward: drive every leg with the opposite sign (the mirror image
            of the forward trial: it starts by reversing); one-way designs
            alternate so the robot comes back.
    """

    k: float
    l_m: float
    variant: Variant = "turn"
    backward: bool = False

    def __post_init__(self) -> None:
        _leg_count(self.k)
        if not math.isfinite(self.l_m) or self.l_m <= 0:
            raise ParameterError(f"l must be a positive length in metres, got {self.l_m!r}")
        # caps that keep every computation on a design bounded (odohil/science/limits.py)
        RANGES["k"].check("k", self.k)
        RANGES["l"].check("l", self.l_m)
        if self.distance_m > TRIAL_DISTANCE_MAX_M:
            raise ParameterError(
                f"one trial of k={self.k:g}, l={self.l_m:g} m drives 2kl = {self.distance_m:g} m; "
                f"at most {TRIAL_DISTANCE_MAX_M:g} m"
            )
        if self.variant not in VARIANTS:
            raise ParameterError(f"variant must be one of {VARIANTS}, got {self.variant!r}")
        if not isinstance(self.backward, bool):
            raise ParameterError(f"backward must be true or false, got {self.backward!r}")

    @property
    def one_way(self) -> bool:
        """True for half-integer k: the trial ends a leg away from its start."""
        return self.n_legs % 2 == 1

    @property
    def forward(self) -> Design:
        """The same design driven forwards."""
        return Design(self.k, self.l_m, self.variant) if self.backward else self

    @property
    def mirrored(self) -> Design:
        """The same design driven the other way."""
        return Design(self.k, self.l_m, self.variant, not self.backward)

    @property
    def variant_text(self) -> str:
        """The variant with ``-backward`` appended for a backward design
        (the ``variant`` column of trial files)."""
        return f"{self.variant}-backward" if self.backward else self.variant

    @property
    def n_legs(self) -> int:
        """Number of legs, 2k."""
        return _leg_count(self.k)

    @property
    def distance_m(self) -> float:
        """Distance driven by one trial, 2kl, metres."""
        return self.n_legs * self.l_m

    def path(self) -> EncoderPath:
        """The encoder path of one trial."""
        return forth_and_back(self.k, self.l_m, self.variant, backward=self.backward)

    def label(self) -> str:
        """A short human-readable name, e.g. ``k=20 l=0.5 m turn``
        (``turn backward`` when driven backwards)."""
        direction = " backward" if self.backward else ""
        return f"k={self.k:g} l={self.l_m:g} m {self.variant}{direction}"


def forth_and_back(
    k: float, l_m: float, variant: Variant = "turn", *, backward: bool = False
) -> EncoderPath:
    """Straight forth and back k times over length l (section 4).

    ``turn``: leg, 180 degree turn, leg, 180 degree turn, ...; with an even
    number of legs the path ends with a turn, so the encoders report the start
    pose. ``reverse``: +l, -l, +l, ... without turning. Half-integer k ends at
    the far end (k = 1/2 is one straight run). ``backward`` negates every leg
    (the turns stay): the mirror image, ending a leg behind the start.
    """
    design = Design(k, l_m, variant, backward)
    n_legs = design.n_legs
    out = -l_m if backward else l_m
    steps: list[Step] = []
    for index in range(n_legs):
        if variant == "turn":
            steps.append(Leg(out))
            if index < n_legs - 1 or n_legs % 2 == 0:
                steps.append(Turn(math.pi))
        else:
            steps.append(Leg(out if index % 2 == 0 else -out))
    return EncoderPath(tuple(steps), name=f"forth-and-back {design.label()}")


@dataclass(frozen=True)
class _Run:
    """The trials of one design: a prefix, then a cycle repeated to the end."""

    n: int
    designs: tuple[Design, ...]
    starts_m: tuple[float, ...]
    cycle_from: int
    step_m: float = 0.0  # forwards only: every trial starts this much further

    def at(self, index: int) -> tuple[Design, float]:
        if self.step_m:
            return self.designs[0], self.starts_m[0] + index * self.step_m
        if index >= len(self.designs):
            period = len(self.designs) - self.cycle_from
            index = self.cycle_from + (index - self.cycle_from) % period
        return self.designs[index], self.starts_m[index]


@dataclass(frozen=True)
class FloorChoreography:
    """Where a sequence of trials takes the robot along its line of travel.

    Every trial starts facing the same way (forth-and-back trials end facing
    their start heading), so positions are metres along that line from the
    first trial's start, forwards positive. Repeated trials of one design fall
    into a cycle, so the cost does not grow with the number of trials.

    Attributes:
        low_m, high_m: the rearmost and foremost points reached, metres.
    """

    runs: tuple[_Run, ...]
    low_m: float
    high_m: float

    @property
    def excursion_m(self) -> float:
        """Length of floor the trials cover, metres (the free floor they need)."""
        return self.high_m - self.low_m

    @property
    def n_trials(self) -> int:
        """Number of trials."""
        return sum(run.n for run in self.runs)

    def trial(self, number: int) -> tuple[Design, float]:
        """Trial ``number`` (1-based): its design as driven and its start, metres."""
        if not 1 <= number <= self.n_trials:
            raise ParameterError(f"trial {number} is outside 1..{self.n_trials}")
        index = number - 1
        for run in self.runs:
            if index < run.n:
                return run.at(index)
            index -= run.n
        raise AssertionError("unreachable")


def trial_extent(design: Design, start_m: float) -> tuple[float, float, float]:
    """(rearmost, foremost, end) positions of one trial started at ``start_m``, metres."""
    if design.backward:
        low, high = start_m - design.l_m, start_m
        end = low if design.one_way else start_m
    else:
        low, high = start_m, start_m + design.l_m
        end = high if design.one_way else start_m
    return low, high, end


def _choose(design: Design, position: float, low: float, high: float) -> Design:
    options = []
    for choice in (design.forward, design.forward.mirrored):
        lo, hi, end = trial_extent(choice, position)
        options.append((max(high, hi) - min(low, lo), abs(end), choice.backward, choice))
    return min(options, key=lambda o: o[:3])[3]


def floor_choreography(
    items: Sequence[tuple[Design, int]], *, alternate: bool = True
) -> FloorChoreography:
    """Choose each trial's direction so the robot stays on as little floor as possible.

    ``items`` are (design, number of trials) in driving order. Greedy, trial
    by trial: the direction (forwards or :attr:`Design.backward`) that keeps
    the covered length smallest; on a tie the one that ends nearer the first
    start, then forwards. Consecutive trials of one one-way design therefore
    go out and back over the same floor (covering l), and a two-way trial
    started at the far end runs backwards. ``alternate=False``: every trial
    forwards (how sessions were driven before).
    """
    runs: list[_Run] = []
    position, low, high = 0.0, 0.0, 0.0
    for design, n in items:
        if not alternate:
            step = design.l_m if design.one_way else 0.0
            runs.append(_Run(n, (design.forward,), (position,), 0, step))
            high = max(high, position + step * (n - 1) + design.l_m)
            position += step * n
            continue
        designs: list[Design] = []
        starts: list[float] = []
        seen: dict[tuple[float, float, float], int] = {}
        cycle_from = 0
        while len(designs) < n:
            key = (round(position, 9), round(low, 9), round(high, 9))
            if key in seen:
                cycle_from = seen[key]
                break
            seen[key] = len(designs)
            choice = _choose(design, position, low, high)
            lo, hi, end = trial_extent(choice, position)
            designs.append(choice)
            starts.append(position)
            low, high, position = min(low, lo), max(high, hi), end
        if len(designs) < n:
            # the rest repeats the cycle; the position at the end follows it
            period = len(designs) - cycle_from
            last = cycle_from + (n - 1 - cycle_from) % period
            _, _, position = trial_extent(designs[last], starts[last])
        runs.append(_Run(n, tuple(designs), tuple(starts), cycle_from))
    return FloorChoreography(tuple(runs), low, high)


def square(side_m: float, counter_clockwise: bool = True) -> EncoderPath:
    """A square of the given side, turning 90 degrees in place at each corner."""
    return regular_polygon(4, side_m, counter_clockwise, name=f"square {side_m:g} m")


def polygonal_circle(radius_m: float, n_sides: int, counter_clockwise: bool = True) -> EncoderPath:
    """A regular polygon with n sides inscribed in a circle of the given radius."""
    if n_sides < 3:
        raise ParameterError(f"a polygon needs at least 3 sides, got {n_sides}")
    if not math.isfinite(radius_m) or radius_m <= 0:
        raise ParameterError(f"radius must be a positive length in metres, got {radius_m!r}")
    side = 2.0 * radius_m * math.sin(math.pi / n_sides)
    return regular_polygon(
        n_sides, side, counter_clockwise, name=f"circle r={radius_m:g} m, {n_sides} sides"
    )


def regular_polygon(
    n_sides: int, side_m: float, counter_clockwise: bool = True, name: str = ""
) -> EncoderPath:
    """A closed regular polygon: n legs, each followed by an exterior turn."""
    if n_sides < 3:
        raise ParameterError(f"a polygon needs at least 3 sides, got {n_sides}")
    if not math.isfinite(side_m) or side_m <= 0:
        raise ParameterError(f"side must be a positive length in metres, got {side_m!r}")
    RANGES["side"].check("side", side_m)
    if n_sides * side_m > TRIAL_DISTANCE_MAX_M:
        raise ParameterError(
            f"a path of {n_sides} sides of {side_m:g} m drives {n_sides * side_m:g} m; "
            f"at most {TRIAL_DISTANCE_MAX_M:g} m"
        )
    if n_sides > 2 * RANGES["k"].high:
        raise ParameterError(f"a polygon has at most {2 * RANGES['k'].high:g} sides, got {n_sides}")
    turn = (2.0 * math.pi / n_sides) * (1.0 if counter_clockwise else -1.0)
    steps: list[Step] = []
    for _ in range(n_sides):
        steps += [Leg(side_m), Turn(turn)]
    return EncoderPath(tuple(steps), name=name or f"polygon {n_sides}x{side_m:g} m")
