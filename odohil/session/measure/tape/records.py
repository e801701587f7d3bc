"""The tape's own journal records: its events, the readings they fold into,
and the context its distance sources see.

The tape source (:class:`~odohil.session.measure.tape.source.TapeSource`) journals each
reading as it is taken; the session state keeps them, per attempt, as an
opaque :class:`~odohil.session.journal.events.SourceReadings` (a
:class:`TapeReadings` here) and hands them back to the source in its context
(``TrialContext.readings``). The tape's distance sources (the operator, the
fake's simulated tape, recorded rows) see the attempt as a
:class:`TapeContext`: the generic context with the distances' names and the
readings taken so far. Kinds (``data`` members in brackets; every one also
names ``trial`` and ``attempt``):

- ``measurement``: one distance [``index``, ``label``, ``value_m``];
- ``measurements_rejected``: the distances of this attempt are discarded and
  taken again [``reason``];
- ``remeasured``: the slip check doubted the trial's pose; the suspect
  distance was taken again, or the operator kept it [``index``, ``label``,
  ``reason``, ``previous_m``, ``value_m`` (absent or null when kept),
  ``kept``]; a kept value flags the trial;
- ``extra_distance``: an ambiguous trial's extra cross distance, asked for by
  name [``start``, ``end`` (screw names), ``label``, ``value_m``].
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace
from typing import ClassVar

from odohil.science.floor_marks import MarkDistances
from odohil.science.robot_description import RobotDescription
from odohil.session.journal.events import SourceEvent, SourceReadings
from odohil.session.measure.protocol import TrialContext

__all__ = [
    "MeasurementsRejected",
    "Remeasured",
    "TapeContext",
]


@dataclass(frozen=True)
class TapeReadings:
    """One attempt's tape readings (a :class:`~odohil.session.journal.events.SourceReadings`).

    Attributes:
        measurements: the distances taken so far, metres, in the robot
            description's order.
        rejections: how many times this attempt's distances were rejected.
        remeasures: how many suspect distances were taken again.
        slip: why the slip check doubts the trial, when the operator kept the
            suspect value ("" otherwise).
        extra: extra cross distances (start screw, end screw, metres) taken
            to settle an ambiguous choice.
    """

    measurements: tuple[float, ...] = ()
    rejections: int = 0
    remeasures: int = 0
    slip: str = ""
    extra: tuple[tuple[str, str, float], ...] = ()

    @property
    def values(self) -> tuple[float, ...]:
        """The distances, metres."""
        return self.measurements

    def marks(self, description: RobotDescription) -> MarkDistances | None:
        """The distances as floor marks of ``description`` (None before any)."""
        return MarkDistances.of(description, self.measurements) if self.measurements else None


def _tape(readings: SourceReadings | None) -> TapeReadings:
    if readings is None:
        return TapeReadings()
    if not isinstance(readings, TapeReadings):
        raise ValueError(f"a tape reading in an attempt measured by {type(readings).__name__}")
    return readings


@dataclass(frozen=True)
class TapeContext(TrialContext):
    """A trial attempt as the tape's distance sources see it: the generic
    context (its ``readings`` the attempt's :class:`TapeReadings`, or None
    before the first) with the names of the distances.

    Attributes:
        labels: names of the tape distances, in the order they are asked for
            (the robot description's: same-screw, then cross distances).
    """

    labels: tuple[str, ...] = ()

    @classmethod
    def of(cls, ctx: TrialContext, labels: tuple[str, ...]) -> TapeContext:
        """``ctx`` (as the engine hands it to the tape) with the distances' names.

        Raises:
            ValueError: ``ctx`` holds another source's readings.
        """
        _tape(ctx.readings)
        generic = {f.name: getattr(ctx, f.name) for f in fields(TrialContext)}
        return cls(**generic, labels=labels)

    @property
    def tape(self) -> TapeReadings:
        """The attempt's tape readings so far."""
        return _tape(self.readings)

    @property
    def measurements(self) -> tuple[float, ...]:
        """The distances already taken, metres."""
        return self.tape.measurements

    @property
    def rejections(self) -> int:
        """How many times this attempt's distances were rejected."""
        return self.tape.rejections

    @property
    def remeasures(self) -> int:
        """How many suspect distances were taken again."""
        return self.tape.remeasures

    @property
    def slip(self) -> str:
        """Why the slip check doubts the trial, once a suspect value was kept."""
        return self.tape.slip

    @property
    def extra(self) -> tuple[tuple[str, str, float], ...]:
        """Extra cross distances taken (start screw, end screw, metres)."""
        return self.tape.extra


@dataclass(frozen=True)
class Measurement(SourceEvent):
    """Distance number ``index`` (``label``), ``value_m`` metres."""

    KIND: ClassVar[str] = "measurement"
    trial: int
    attempt: int
    index: int
    value_m: float
    label: str = ""

    def fold(self, readings: SourceReadings | None) -> TapeReadings:
        """The readings with this distance appended (it must be the next one)."""
        tape = _tape(readings)
        if self.index != len(tape.measurements):
            raise ValueError(
                f"measurement {self.index} where {len(tape.measurements)} was expected"
            )
        return replace(tape, measurements=(*tape.measurements, self.value_m))


@dataclass(frozen=True)
class MeasurementsRejected(SourceEvent):
    """The attempt's distances explain no rigid motion (``reason``): taken again."""

    KIND: ClassVar[str] = "measurements_rejected"
    trial: int
    attempt: int
    reason: str = ""

    def fold(self, readings: SourceReadings | None) -> TapeReadings:
        """No distances (nor extra ones) any more; one rejection more."""
        tape = _tape(readings)
        return replace(tape, measurements=(), rejections=tape.rejections + 1, extra=())


@dataclass(frozen=True)
class Remeasured(SourceEvent):
    """The slip check suspected distance ``index``: taken again (``value_m``)
    or kept (``kept``: the trial is flagged, ``reason``)."""

    KIND: ClassVar[str] = "remeasured"
    trial: int
    attempt: int
    index: int
    reason: str
    kept: bool
    previous_m: float | None = None
    value_m: float | None = None
    label: str = ""

    def fold(self, readings: SourceReadings | None) -> TapeReadings:
        """The readings with the distance replaced, or the slip noted."""
        tape = _tape(readings)
        if not 0 <= self.index < len(tape.measurements):
            raise ValueError(f"re-measured distance {self.index} was not taken")
        if self.kept:
            return replace(tape, slip=self.reason)
        if self.value_m is None:
            raise ValueError("a re-measured distance without its value")
        values = list(tape.measurements)
        values[self.index] = self.value_m
        return replace(tape, measurements=tuple(values), remeasures=tape.remeasures + 1)


@dataclass(frozen=True)
class ExtraDistance(SourceEvent):
    """An ambiguous trial's extra cross distance from the start mark of screw
    ``start`` to the end mark of ``end`` (``label``), ``value_m`` metres."""

    KIND: ClassVar[str] = "extra_distance"
    trial: int
    attempt: int
    start: str
    end: str
    value_m: float
    label: str = ""

    def fold(self, readings: SourceReadings | None) -> TapeReadings:
        """The readings with the extra distance."""
        tape = _tape(readings)
        return replace(tape, extra=(*tape.extra, (self.start, self.end, self.value_m)))
