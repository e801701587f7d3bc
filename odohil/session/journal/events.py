"""The typed events of a session journal, and their one JSON codec.

Every event kind is a frozen dataclass (:class:`Event` subclass) whose
``KIND`` is the journal record's ``kind`` and whose field names are the
members of the record's ``data`` object (the names journals have always
used, so that every journal written by an earlier odohil still replays).
:func:`encode` and :func:`decode` are the only places an event becomes JSON
or JSON an event (the journal's edge, odohil/session/journal/file.py); the engine,
the sources and the CLI handle the dataclasses.

The codec is generic, driven by the field types: ``int``, ``float``, ``str``,
``bool``, tuples (fixed or ``tuple[X, ...]``), ``Mapping[str, Any]`` (JSON
objects kept as they are), :class:`~odohil.session.plans.plan.Plan` and ``X | None``.
A field whose value is None and whose default is None is left out of the
record; a member missing from a record takes the field's default (older
journals lack some); a field marked :data:`REST` takes every member no other
field names (the ``solved`` record's source details, the ``resumed`` note);
a field whose metadata names a ``member`` is journaled under that name (the
name journals have always used, where the field's is more general).

The events of the session's life are here; a pose source's own readings
(the tape's distances, rejections, re-measures, extra distances) are
:class:`SourceEvent` subclasses in the source's module
(odohil/session/measure/tape/records.py), folded into its own
:class:`SourceReadings` record; their modules are listed in
:data:`SOURCE_EVENT_MODULES` so that any journal decodes.
"""

from __future__ import annotations

import importlib
import types
from collections.abc import Callable, Mapping
from dataclasses import MISSING, Field, dataclass, field, fields
from typing import Any, ClassVar, Protocol, Union, get_args, get_origin, get_type_hints

from odohil.errors import ParameterError
from odohil.science.floor_marks import MarkDistances
from odohil.science.frames import Pose
from odohil.science.robot_description import RobotDescription
from odohil.session.plans.plan import Plan

__all__ = [
    "ESTIMATE",
    "FINISHED",
    "FORMAT",
    "MOTION_DONE",
    "MOTION_START",
    "OPERATOR",
    "PLAN",
    "REST",
    "RESUMED",
    "ROBOT",
    "SESSION",
    "SOLVED",
    "SOURCE_EVENT_MODULES",
    "START_POSE",
    "STOPPED",
    "STOP_UNCONFIRMED",
    "TORN_RECORD",
    "TRIAL_START",
    "VOID",
    "Estimate",
    "Event",
    "Finished",
    "MotionDone",
    "MotionStart",
    "PlanSet",
    "Resumed",
    "RobotConnected",
    "SessionHeader",
    "Solved",
    "SourceEvent",
    "SourceReadings",
    "StartPoseChecked",
    "StopUnconfirmed",
    "Stopped",
    "TornRecordKept",
    "TrialStart",
    "Void",
    "decode",
    "encode",
    "event_types",
]

FORMAT = 1
"""Version of the journal's event schema."""

OPERATOR = "operator"
"""The wizard's measurement, as journaled in the session header's ``measure``:
an operator with a tape at the terminal (no ``--measure`` form: ``odohil
wizard`` asks the distances)."""

REST = {"rest": True}
"""Field metadata: this ``Mapping`` field holds the members no other field names."""

SOURCE_EVENT_MODULES = ("odohil.session.measure.tape.records",)
"""Modules that define pose sources' own events (imported before the first decode)."""

JsonObject = Mapping[str, Any]
"""A JSON object as the journal holds it (kept as it is)."""


class Event:
    """One journal event; subclasses are frozen dataclasses with a ``KIND``."""

    KIND: ClassVar[str] = ""
    _TYPES: ClassVar[dict[str, type[Event]]] = {}

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if cls.KIND:
            known = Event._TYPES.get(cls.KIND)
            if known is not None and known.__qualname__ != cls.__qualname__:
                raise TypeError(f"two events of kind {cls.KIND!r}: {known} and {cls}")
            Event._TYPES[cls.KIND] = cls


class SourceReadings(Protocol):
    """A pose source's own record of one trial attempt's readings, built from its
    :class:`SourceEvent` s; opaque to the session state and the engine, handed
    back to the source in ``TrialContext.readings``."""

    @property
    def values(self) -> tuple[float, ...]:
        """The readings the pose was solved from, in order (kept with the trial,
        so that the session can be solved again offline; the tape: its
        distances, metres)."""
        ...

    def marks(self, description: RobotDescription) -> MarkDistances | None:
        """The floor-mark distances the pose was solved from, for a trial set
        (odohil/session/trials/trial_file.py) that is solved again offline; None
        for a source that measures poses."""
        ...


class SourceEvent(Event):
    """A reading a pose source journals while it measures an attempt (``trial``,
    ``attempt``): folded into the attempt's :class:`SourceReadings`."""

    trial: int
    attempt: int

    def fold(self, readings: SourceReadings | None) -> SourceReadings:
        """The attempt's readings after this event.

        Raises:
            ValueError: the event does not fit the readings (the message says why).
        """
        raise NotImplementedError


# --- the session's life -------------------------------------------------------


@dataclass(frozen=True)
class SessionHeader(Event):
    """Record 1 of every journal: what the session is.

    Attributes:
        format: the journal's event schema version.
        odohil: the odohil version that started the session.
        robot_toml: the robot description's TOML text (journaled whole).
        robot_path: where the description was read from.
        measure: the measurement source (``fake``, ``file``, ``operator``, ``tcp``).
        settings: anything else worth keeping (port, seed, time scale...).
        plan: the plan (journaled whole so that a session always has it).
        extra: members this odohil does not know (kept).
    """

    KIND: ClassVar[str] = "session"
    format: int
    odohil: str | None = None
    robot_toml: str | None = None
    robot_path: str | None = None
    measure: str | None = None
    settings: JsonObject = field(default_factory=dict)
    plan: Plan | None = None
    extra: JsonObject = field(default_factory=dict, metadata=REST)

    @property
    def robot_source(self) -> str:
        """Where the robot description was read from ("" when not said)."""
        return str(self.robot_path or "")

    def get(self, member: str, default: Any = None) -> Any:
        """The record's member ``member`` (for code that still reads the header
        as the JSON object it was; prefer the attributes)."""
        return encode(self)[1].get(member, default)

    def __getitem__(self, member: str) -> Any:
        return encode(self)[1][member]

    def __contains__(self, member: object) -> bool:
        return member in encode(self)[1]


@dataclass(frozen=True)
class PlanSet(Event):
    """The plan, for a session record without one (the record is the plan's JSON)."""

    KIND: ClassVar[str] = "plan"
    plan: Plan


@dataclass(frozen=True)
class RobotConnected(Event):
    """The robot's identity and settings, after each connect."""

    KIND: ClassVar[str] = "robot"
    connection: JsonObject = field(default_factory=dict)
    motion: JsonObject = field(default_factory=dict)
    state: JsonObject | None = None


@dataclass(frozen=True)
class Resumed(Event):
    """A later process took the session over (``note``: what it says about itself)."""

    KIND: ClassVar[str] = "resumed"
    note: JsonObject = field(default_factory=dict, metadata=REST)


@dataclass(frozen=True)
class TornRecordKept(Event):
    """The torn last record found on resume was kept aside in ``file``."""

    KIND: ClassVar[str] = "torn_record"
    file: str = ""
    line: int | None = None
    bytes: int | None = None
    reason: str = ""


@dataclass(frozen=True)
class StartPoseChecked(Event):
    """Where the robot stands against where trial ``trial`` starts
    (odohil/session/run/start_pose.py): poses (x m, y m, theta rad)."""

    KIND: ClassVar[str] = "start_pose"
    actual: Pose
    ok: bool
    trial: int | None = None
    expected: Pose | None = None


@dataclass(frozen=True)
class TrialStart(Event):
    """The robot was re-zeroed and the start marks made.

    Attributes:
        design: index of the trial's design in the plan.
        backward: driven with every leg reversed (None in old journals).
        zeroed: the encoder sample after re-zeroing.
        start: the source's start data.
    """

    KIND: ClassVar[str] = "trial_start"
    trial: int
    attempt: int
    design: int
    backward: bool | None = None
    zeroed: JsonObject | None = None
    start: JsonObject = field(default_factory=dict)


@dataclass(frozen=True)
class MotionStart(Event):
    """The motion of the attempt was started."""

    KIND: ClassVar[str] = "motion_start"
    trial: int
    attempt: int


@dataclass(frozen=True)
class MotionDone(Event):
    """The motion finished.

    Attributes:
        encoder_end_pose: (x m, y m, theta rad) the odometry reported.
        duration_s: the motion's wall time, s.
        trajectory: rows (t s, x m, y m, theta rad).
        end: the source's end data.
    """

    KIND: ClassVar[str] = "motion_done"
    trial: int
    attempt: int
    encoder_end_pose: Pose
    duration_s: float | None = None
    trajectory: tuple[tuple[float, ...], ...] = ()
    end: JsonObject = field(default_factory=dict)


@dataclass(frozen=True)
class Solved(Event):
    """The pose change; the trial is complete.

    Attributes:
        pose_change: (dx m, dy m, dtheta rad).
        cov: its 3x3 covariance, rows.
        clear_cut: the source is sure of the pose.
        reason: why the pose is in doubt ("" when clear-cut).
        flag_reason: why the source flagged the trial (None: not flagged;
            journaled as ``slip``, the tape's slip check being the first
            source to flag a trial).
        ambiguous: two candidate poses stay plausible (left out of every estimate).
        candidates: their poses.
        details: the source's details (the tape's ``chi2``, ``check``...).
    """

    KIND: ClassVar[str] = "solved"
    trial: int
    attempt: int
    pose_change: Pose
    cov: tuple[Pose, Pose, Pose]
    clear_cut: bool
    reason: str = ""
    flag_reason: str | None = field(default=None, metadata={"member": "slip"})
    ambiguous: bool | None = None
    candidates: tuple[Pose, ...] | None = None
    details: JsonObject = field(default_factory=dict, metadata=REST)


@dataclass(frozen=True)
class Estimate(Event):
    """The live estimate over ``n_trials`` trials (``result``: its JSON object,
    None when the fit failed: ``error`` says why)."""

    KIND: ClassVar[str] = "estimate"
    n_trials: int
    result: JsonObject | None = None
    error: str | None = None


@dataclass(frozen=True)
class Void(Event):
    """The attempt is discarded and the trial redone."""

    KIND: ClassVar[str] = "void"
    trial: int
    attempt: int
    reason: str = ""


@dataclass(frozen=True)
class Stopped(Event):
    """The process stopped early and the robot reported that it stopped
    (``state``: its encoder sample)."""

    KIND: ClassVar[str] = "stopped"
    reason: str = ""
    message: str = ""
    robot: str = "stopped"
    state: JsonObject | None = None


@dataclass(frozen=True)
class StopUnconfirmed(Event):
    """The process stopped early and the robot did NOT report that it stopped."""

    KIND: ClassVar[str] = "stop_unconfirmed"
    reason: str = ""
    message: str = ""
    detail: str = ""


@dataclass(frozen=True)
class Finished(Event):
    """The plan is done (``n_trials`` completed)."""

    KIND: ClassVar[str] = "finished"
    n_trials: int | None = None


# The record kinds of the session's life, for readers of raw records (the
# events' ``KIND``s; a pose source's own kinds are its events', e.g.
# odohil/session/measure/tape/records.py).
SESSION = SessionHeader.KIND
PLAN = PlanSet.KIND
ROBOT = RobotConnected.KIND
RESUMED = Resumed.KIND
TORN_RECORD = TornRecordKept.KIND
TRIAL_START = TrialStart.KIND
MOTION_START = MotionStart.KIND
MOTION_DONE = MotionDone.KIND
SOLVED = Solved.KIND
ESTIMATE = Estimate.KIND
VOID = Void.KIND
STOPPED = Stopped.KIND
STOP_UNCONFIRMED = StopUnconfirmed.KIND
FINISHED = Finished.KIND
START_POSE = StartPoseChecked.KIND


# --- the codec ----------------------------------------------------------------


def event_types() -> Mapping[str, type[Event]]:
    """Every event kind this odohil reads, by ``kind``."""
    if not _loaded:
        for module in SOURCE_EVENT_MODULES:
            importlib.import_module(module)
        _loaded.append(True)
    return Event._TYPES


_loaded: list[bool] = []


def encode(event: Event) -> tuple[str, dict[str, Any]]:
    """The record ``kind`` and JSON ``data`` of an event."""
    if isinstance(event, PlanSet):
        return event.KIND, dict(event.plan.to_json())
    data: dict[str, Any] = {}
    rest: dict[str, Any] = {}
    for f in fields(event):  # type: ignore[arg-type]
        value = getattr(event, f.name)
        if f.metadata.get("rest"):
            rest = dict(value)
        elif value is None and f.default is None:
            continue
        else:
            data[_member(f)] = _to_json(value)
    return event.KIND, {**rest, **data}


def _member(f: Field[Any]) -> str:
    """The JSON member a field is journaled as."""
    return str(f.metadata.get("member", f.name))


def decode(kind: str, data: Mapping[str, Any]) -> Event:
    """The event of a record.

    Raises:
        ValueError: an unknown kind, a missing member or one of the wrong type
            (the message names it).
    """
    cls = event_types().get(kind)
    if cls is None:
        raise ValueError(f"unknown event kind {kind!r}")
    if cls is PlanSet:
        try:
            return PlanSet(Plan.from_json(data))
        except ParameterError as exc:
            raise ValueError(f"bad plan: {exc}") from None
    hints = _hints(cls)
    values: dict[str, Any] = {}
    named: set[str] = set()
    rest_field = ""
    for f in fields(cls):  # type: ignore[arg-type]
        if f.metadata.get("rest"):
            rest_field = f.name
            continue
        member = _member(f)
        named.add(member)
        if member not in data:
            if f.default is MISSING and f.default_factory is MISSING:
                raise ValueError(f"no member {member!r}")
            continue
        values[f.name] = _from_json(data[member], hints[f.name], member)
    if rest_field:
        values[rest_field] = {k: v for k, v in data.items() if k not in named and k not in hints}
    return cls(**values)


_HINTS: dict[type, dict[str, Any]] = {}


def _hints(cls: type) -> dict[str, Any]:
    if cls not in _HINTS:
        _HINTS[cls] = get_type_hints(cls)
    return _HINTS[cls]


def _to_json(value: Any) -> Any:
    if isinstance(value, tuple | list):
        return [_to_json(v) for v in value]
    if isinstance(value, Mapping):
        return dict(value)
    if isinstance(value, Plan):
        return value.to_json()
    return value


def _from_json(value: Any, hint: Any, where: str) -> Any:
    """``value`` as type ``hint``; ValueError naming ``where`` when it is not."""
    if hint is Any:
        return value
    origin = get_origin(hint)
    reader = _READERS.get(origin if origin is not None else hint)
    if reader is None:
        raise TypeError(f"{where}: the journal codec cannot read {hint!r}")
    return reader(value, hint, where)


def _scalar(kind: type, test: Callable[[Any], bool], what: str) -> Callable[[Any, Any, str], Any]:
    def read(value: Any, hint: Any, where: str) -> Any:
        if not test(value):
            raise ValueError(f"{where}: {value!r} is not {what}")
        return kind(value)

    return read


def _optional(value: Any, hint: Any, where: str) -> Any:
    options = [a for a in get_args(hint) if a is not type(None)]
    if value is None:
        if len(options) < len(get_args(hint)):
            return None
        raise ValueError(f"{where}: null")
    return _from_json(value, options[0], where)


def _tuple(value: Any, hint: Any, where: str) -> tuple[Any, ...]:
    if not isinstance(value, list):
        raise ValueError(f"{where}: {value!r} is not a list")
    args = get_args(hint)
    if len(args) == 2 and args[1] is Ellipsis:
        return tuple(_from_json(v, args[0], where) for v in value)
    if len(value) != len(args):
        raise ValueError(f"{where}: {len(value)} values where {len(args)} are expected")
    return tuple(_from_json(v, a, where) for v, a in zip(value, args, strict=True))


def _object(value: Any, hint: Any, where: str) -> Mapping[str, Any]:
    if not isinstance(value, dict):
        raise ValueError(f"{where}: {value!r} is not an object")
    return value


def _plan(value: Any, hint: Any, where: str) -> Plan:
    try:
        return Plan.from_json(value)
    except ParameterError as exc:
        raise ValueError(f"{where}: bad plan: {exc}") from None


def _is_number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


_READERS: dict[Any, Callable[[Any, Any, str], Any]] = {
    bool: _scalar(bool, lambda v: isinstance(v, bool), "true or false"),
    int: _scalar(int, lambda v: _is_number(v) and isinstance(v, int), "an integer"),
    float: _scalar(float, _is_number, "a number"),
    str: _scalar(str, lambda v: isinstance(v, str), "text"),
    Union: _optional,
    types.UnionType: _optional,
    tuple: _tuple,
    Mapping: _object,
    Plan: _plan,
}
