"""The operator's entry of tape distances: what a typed line means.

The logic behind the wizard's distance prompts (odohil/cli/wizard.py only
reads lines and renders): :func:`parse_metres` turns ``0.012``, ``12 mm`` or
``1.2 cm`` into metres; :func:`expected_ranges` says what the model expects of
each distance, from the engine's prediction of the pose change (at the live
estimate, else the robot description's ``[priors]``: one place,
:func:`~odohil.session.measure.tape.source.prediction`); :class:`TapeEntry` is the state
machine of one attempt's distances (which distance is asked next, ``back``
to correct the value typed just before, the range checks, the values a
rejection did not name kept); :func:`kept_after` is the re-measure
bookkeeping of a typed rejection, :class:`TapeEntries` that of a whole session.
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np

from odohil import units
from odohil.errors import InconsistentMeasurementError, MeasurementError
from odohil.science.floor_marks import PosePrior, marks_from_pose
from odohil.science.path_designs import PathDesign
from odohil.science.paths import Design
from odohil.science.robot_description import RobotDescription
from odohil.session.measure.tape.records import TapeContext
from odohil.session.measure.tape.source import check_distance, prediction

BACK_WORDS = ("back", "-")
"""What the operator types at a distance prompt to correct the value typed just before."""
INSTRUCTIONS = (
    "Type each distance in metres, or with a unit (12 mm, 1.2 cm); "
    f"type {' or '.join(BACK_WORDS)} to correct the value typed just before."
)
"""What the operator is told before the first distance of a round."""
SPREAD_SIGMAS = 4.0
"""Half-width of an expected range, in standard deviations of the predicted distance."""
SAMPLES = 400
"""Poses drawn from the prediction to find the distances' spread."""
_NUMBER = re.compile(r"^\s*(?P<number>[^a-z\s]*|nan|inf|[+-]inf|infinity)\s*(?P<unit>mm|cm|m)?\s*$")


def parse_metres(text: str, label: str) -> float:
    """A typed distance in metres: ``0.012``, ``12 mm``, ``1.2cm``, ``0.012 m``.
    The one parse of what the operator typed: the number and its unit become
    metres here (:data:`odohil.units.METRES_PER_LENGTH_UNIT`), and from here on
    the distance stays that float, up to its journal record.

    Raises:
        MeasurementError: not a number (with an optional unit), or not a
            distance (:func:`~odohil.session.measure.tape.source.check_distance`).
    """
    match = _NUMBER.match(text.strip().lower())
    refusal = f"{text.strip()!r} is not a number of metres (e.g. 0.012, 12 mm or 1.2 cm)"
    if match is None or not match.group("number"):
        raise MeasurementError(refusal)
    try:
        number = float(match.group("number"))
    except ValueError:
        raise MeasurementError(refusal) from None
    return check_distance(units.to_metres(number, match.group("unit") or "m"), label)


def parse_optional_metres(text: str, label: str) -> float | None:
    """A re-measured or extra distance: metres, or None for an empty line
    (the operator keeps the value, or cannot measure it).

    Raises:
        MeasurementError: see :func:`parse_metres`.
    """
    return parse_metres(text, label) if text.strip() else None


@dataclass(frozen=True)
class ExpectedRange:
    """What the model expects of one distance, metres.

    Attributes:
        low, high: the expected range (model spread, :data:`SPREAD_SIGMAS`
            sigma, plus 3 sigma of tape error).
        limit: beyond this the value is physically implausible for the trial.
    """

    low: float
    high: float
    limit: float

    def hint(self) -> str:
        """``expected LOW to HIGH m``."""
        return f"expected {self.low:.4f} to {self.high:.4f} m"


def expected_ranges(
    description: RobotDescription, design: Design | PathDesign, predicted: PosePrior, seed: int = 0
) -> tuple[ExpectedRange, ...]:
    """Per distance, the range the model expects: :data:`SAMPLES` poses drawn
    (seeded) from ``predicted`` through the forward model."""
    rng = np.random.default_rng(seed)
    poses = rng.multivariate_normal(predicted.mean, predicted.cov, SAMPLES, method="eigh")
    values = np.array([marks_from_pose(description, pose).as_array() for pose in poses])
    spread = SPREAD_SIGMAS * values.std(axis=0) + 3.0 * description.sigma_m
    low = np.clip(values.mean(axis=0) - spread, 0.0, None)
    high = values.mean(axis=0) + spread
    radius = float(np.max(np.hypot(description.positions()[:, 0], description.positions()[:, 1])))
    limit = design.distance_m + 2.0 * radius + 0.1
    return tuple(ExpectedRange(float(a), float(b), limit) for a, b in zip(low, high, strict=True))


def attempt_ranges(ctx: TapeContext, description: RobotDescription) -> tuple[ExpectedRange, ...]:
    """The expected ranges of a trial attempt's distances, from the engine's
    prediction (:func:`~odohil.session.measure.tape.source.prediction`)."""
    return expected_ranges(description, ctx.design, prediction(ctx, description), ctx.trial)


def kept_after(
    rejection: InconsistentMeasurementError, labels: Sequence[str], measurements: Sequence[float]
) -> dict[int, float]:
    """The distances a rejection did not name, by index, kept for the next
    round; none when it names none (or all): then every distance is retaken."""
    named = {i for i, label in enumerate(labels) if label in rejection.labels}
    if not named or len(named) >= len(measurements):
        return {}
    return {i: value for i, value in enumerate(measurements) if i not in named}


@dataclass(frozen=True)
class Question:
    """The distance asked now.

    Attributes:
        index, label: which distance.
        expected: what the model expects of it.
        back_to: the label of the value ``back`` would correct (None: nothing).
        trial: the trial it belongs to (``Trial 3/60``; may be empty).
    """

    index: int
    label: str
    expected: ExpectedRange
    back_to: str | None
    trial: str = ""

    @property
    def prompt(self) -> str:
        """What the operator is asked: ``Trial 3/60, d1 (screw A), metres (expected ...): ``."""
        back = f"; back: correct {self.back_to}" if self.back_to else ""
        where = f"{self.trial}, " if self.trial else ""
        return f"{where}{self.label}, metres ({self.expected.hint()}{back}): "


@dataclass(frozen=True)
class Reply:
    """What one typed line did: ``entered`` (taken), ``correct`` (``back``:
    the value typed just before is asked again), ``no_back`` (nothing to go
    back to), ``refused`` (not a distance, or implausible) or ``check``
    (outside the expected range: typed again, it is kept); ``message`` says so."""

    kind: Literal["entered", "correct", "no_back", "refused", "check"]
    message: str = ""


class TapeEntry:
    """One attempt's distances as the operator types them, fed one line at a time.

    A value is handed over (:meth:`take`) only once the next distance asked
    has been typed too, so that ``back`` at that prompt corrects it; the last
    one at once. Distances in ``kept`` (a rejection did not name them) are
    handed over without asking.
    """

    def __init__(
        self,
        labels: Sequence[str],
        ranges: Sequence[ExpectedRange],
        kept: Mapping[int, float] | None = None,
        trial: str = "",
    ) -> None:
        self.labels = tuple(labels)
        self.ranges = tuple(ranges)
        self.kept = dict(kept or {})
        self.trial = trial
        self._typed: dict[int, float] = {}
        self._handed: set[int] = set()
        self._first = 0
        self._unconfirmed: tuple[int, float] | None = None

    @classmethod
    def for_attempt(
        cls, ctx: TapeContext, description: RobotDescription, kept: Mapping[int, float] | None
    ) -> TapeEntry:
        """The entry of a trial attempt, its ranges from the session's prediction."""
        trial = f"Trial {ctx.trial}/{ctx.n_trials}"
        return cls(ctx.labels, attempt_ranges(ctx, description), kept, trial)

    def _next_asked(self, index: int) -> int | None:
        return next((j for j in range(index + 1, len(self.labels)) if j not in self.kept), None)

    def take(self, index: int) -> float | None:
        """Distance ``index`` in metres if it can be handed over now, else None
        (then :meth:`question` is asked and the answer :meth:`feed`)."""
        if index in self.kept:
            return self.kept[index]
        self._first = max(self._first, index)
        following = self._next_asked(index)
        if index in self._typed and (following is None or following in self._typed):
            self._handed.add(index)
            return self._typed[index]
        return None

    def _pending(self, asked: int) -> int | None:
        """The typed value not yet handed over that ``back`` would correct."""
        return next((i for i in self._typed if i < asked and i not in self._handed), None)

    def question(self) -> Question:
        """The distance asked now."""
        index = next(
            j
            for j in range(self._first, len(self.labels))
            if j not in self.kept and j not in self._typed
        )
        pending = self._pending(index)
        back_to = None if pending is None else self.labels[pending]
        return Question(index, self.labels[index], self.ranges[index], back_to, self.trial)

    def feed(self, text: str) -> Reply:
        """Take one typed line as the answer to :meth:`question`."""
        asked = self.question()
        if text.strip().lower() in BACK_WORDS:
            pending = self._pending(asked.index)
            if pending is None:
                return Reply(
                    "no_back",
                    "nothing to go back to: only the value typed just before can be corrected, "
                    "and the earlier ones are saved; type this distance",
                )
            del self._typed[pending]
            return Reply("correct", f"Correct {self.labels[pending]}:")
        try:
            value = parse_metres(text, asked.label)
        except MeasurementError as exc:
            return Reply("refused", f"{exc}; type it again")
        expected = asked.expected
        if value > expected.limit:
            return Reply(
                "refused",
                f"{value:g} m is implausible: the marks of this trial cannot be more "
                f"than {expected.limit:.2f} m apart; type it again",
            )
        outside = not expected.low <= value <= expected.high
        if outside and self._unconfirmed != (asked.index, value):
            self._unconfirmed = (asked.index, value)
            return Reply(
                "check",
                f"{value:g} m is outside the expected range ({expected.hint()}); "
                "type the same value again to keep it, or the corrected one",
            )
        self._unconfirmed = None
        self._typed[asked.index] = value
        return Reply("entered")


class TapeEntries:
    """The operator's entries over a session: one :class:`TapeEntry` per round
    of an attempt (trial, attempt, rejections; a rejection starts a round that
    keeps the distances it did not name), and which attempts were introduced."""

    def __init__(self, description: RobotDescription) -> None:
        self.description = description
        self._entries: dict[tuple[int, int, int], TapeEntry] = {}
        self._kept: dict[tuple[int, int, int], dict[int, float]] = {}
        self._seen: set[tuple[int, int]] = set()

    def first_sight(self, ctx: TapeContext) -> bool:
        """Whether ``ctx``'s attempt is seen for the first time (its header is due)."""
        new = (ctx.trial, ctx.attempt) not in self._seen
        self._seen.add((ctx.trial, ctx.attempt))
        return new

    def entry(self, ctx: TapeContext) -> tuple[TapeEntry, bool]:
        """The entry of ``ctx``'s round, and whether it is new (its instructions are due)."""
        key = (ctx.trial, ctx.attempt, ctx.rejections)
        new = key not in self._entries
        if new:
            self._entries[key] = TapeEntry.for_attempt(ctx, self.description, self._kept.get(key))
        return self._entries[key], new

    def rejected(
        self, ctx: TapeContext, rejection: InconsistentMeasurementError
    ) -> dict[int, float]:
        """The distances the next round keeps (:func:`kept_after`), by index."""
        kept = kept_after(rejection, ctx.labels, ctx.measurements)
        self._kept[(ctx.trial, ctx.attempt, ctx.rejections + 1)] = kept
        return kept
