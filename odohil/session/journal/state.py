"""The session state a journal replays to.

The events are typed (odohil/session/journal/events.py; the tape's own in
odohil/session/measure/tape/records.py, with the JSON members of each kind); this
module applies them to the state one at a time, by a dispatch table on the
event's type (:func:`apply`). A pose source's readings (``SourceEvent``) are
folded into the open attempt's opaque ``readings``, which the state hands
back to the engine and on to the source without looking inside.

A trial is identified by its number in the plan (1-based); each try at it is
an attempt (1, 2, ...). A trial counts once it has a ``solved`` record, and a
second ``solved`` for the same trial is a :class:`JournalError`.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field, replace
from enum import Enum
from pathlib import Path
from typing import Any, TypeVar, cast

import numpy as np

from odohil.errors import JournalError, OdohilError, ParameterError
from odohil.science.estimators import Observation
from odohil.science.limits import RANGES
from odohil.science.path_designs import PathDesign
from odohil.science.path_trials import Direction, PathTrial
from odohil.science.paths import Design
from odohil.science.robot_description import RobotDescription
from odohil.session import plugins
from odohil.session.addresses import parse_tcp_url
from odohil.session.journal.events import (
    FORMAT,
    OPERATOR,
    SESSION,
    Estimate,
    Event,
    Finished,
    MotionDone,
    MotionStart,
    PlanSet,
    Resumed,
    RobotConnected,
    SessionHeader,
    Solved,
    SourceEvent,
    SourceReadings,
    StartPoseChecked,
    Stopped,
    StopUnconfirmed,
    TornRecordKept,
    TrialStart,
    Void,
    decode,
)
from odohil.session.journal.file import Record, TornRecord, read_journal
from odohil.session.plans.plan import Plan, TrialShape, check_session_plan, driven_backward
from odohil.session.robots.registry import parse_description as parse_robot_description
from odohil.session.trials.trial_file import Trial, TrialSet
from odohil.units import wrap_angle

__all__ = [
    "CompletedTrial",
    "OpenTrial",
    "Phase",
    "SessionState",
    "apply",
    "description_of_header",
    "load_session",
    "replay",
    "session_path_trials",
    "session_trials",
]


class Phase(Enum):
    """Where an open (not yet solved) trial attempt stands."""

    MARKED = "marked"
    """Re-zeroed and start marks made; the motion was not started."""
    MOVING = "moving"
    """The motion was started and did not report its end."""
    MEASURING = "measuring"
    """The motion finished; the source is measuring (its readings may all be in)."""


@dataclass(frozen=True)
class OpenTrial:
    """A trial attempt that is under way.

    Attributes:
        trial: trial number in the plan (1-based).
        attempt: attempt number (1-based).
        design_index: index of its design in the plan.
        phase: where it stands.
        start: the measurement source's start-mark data.
        encoder_end_pose: (x m, y m, theta rad) once the motion is done.
        trajectory: rows (t s, x m, y m, theta rad) of the motion.
        end: the measurement source's end-mark data once the motion is done.
        readings: the pose source's own record of its readings so far (the
            tape's: odohil/session/measure/tape/records.py), None before the first.
    """

    trial: int
    attempt: int
    design_index: int
    phase: Phase
    start: Mapping[str, Any]
    encoder_end_pose: tuple[float, float, float] | None = None
    trajectory: tuple[tuple[float, ...], ...] = ()
    end: Mapping[str, Any] = field(default_factory=dict)
    readings: SourceReadings | None = None


@dataclass(frozen=True)
class CompletedTrial:
    """A trial with its solved pose change.

    Attributes:
        trial: trial number in the plan (1-based).
        attempt: the attempt that completed it.
        design: its design as driven (forth-and-back, or a general path).
        design_index: index of the design in the plan.
        encoder_end_pose: (x m, y m, theta rad) the encoders reported.
        pose_change: solved (dx m, dy m, dtheta rad).
        cov: 3x3 covariance of ``pose_change`` (m^2, m rad, rad^2), rows.
        clear_cut: whether the solver was sure of its choice.
        start: the measurement source's start data (e.g. the true start pose).
        end: the measurement source's end data.
        note: why the solution is in doubt (empty when clear-cut).
        seq: sequence number (= line in the journal file) of the ``solved`` record.
        ambiguous: two candidate poses stayed plausible; the trial is left
            out of every estimate.
        candidates: the plausible poses of an ambiguous trial (dx m, dy m, dtheta rad).
        flag_reason: why the source flagged the trial (empty when it did not;
            the tape: the slip check's doubt).
        readings: the pose source's own record of the attempt's readings
            (the readings the pose was solved from: ``readings.values``;
            None for a source that measures poses).
    """

    trial: int
    attempt: int
    design: TrialShape
    design_index: int
    encoder_end_pose: tuple[float, float, float]
    pose_change: tuple[float, float, float]
    cov: tuple[tuple[float, float, float], ...]
    clear_cut: bool
    start: Mapping[str, Any]
    end: Mapping[str, Any]
    note: str = ""
    seq: int = 0
    ambiguous: bool = False
    candidates: tuple[tuple[float, float, float], ...] = ()
    flag_reason: str = ""
    readings: SourceReadings | None = None


@dataclass(frozen=True)
class SessionState:
    """A session as its journal tells it.

    Attributes:
        header: the ``session`` record.
        plan: the plan, once journaled.
        completed: completed trials, in completion order.
        open_trial: the attempt under way, if any.
        voided: number of voided attempts.
        attempts: the last attempt number of each trial started.
        last_estimate: the latest ``estimate`` record.
        finished: whether a ``finished`` record closes the session.
        n_records: number of records replayed.
    """

    header: SessionHeader
    plan: Plan | None = None
    completed: tuple[CompletedTrial, ...] = ()
    open_trial: OpenTrial | None = None
    voided: int = 0
    attempts: Mapping[int, int] = field(default_factory=dict)
    last_estimate: Estimate | None = None
    finished: bool = False
    n_records: int = 0

    @property
    def done_trials(self) -> frozenset[int]:
        """Numbers of the completed trials."""
        return frozenset(t.trial for t in self.completed)

    def next_trial(self) -> int | None:
        """The lowest trial number not yet completed, or None when all are."""
        if self.plan is None:
            return None
        done = self.done_trials
        for trial in range(1, self.plan.n_trials + 1):
            if trial not in done:
                return trial
        return None

    def next_attempt(self, trial: int) -> int:
        """The attempt number a new try at ``trial`` gets."""
        return self.attempts.get(trial, 0) + 1


def replay(records: Iterable[Record]) -> SessionState:
    """Replay journal records into the session state.

    Raises:
        JournalError: the records do not tell a consistent session (the
            message names the record's sequence number).
    """
    state: SessionState | None = None
    for record in records:
        if state is None:
            if record.kind != SESSION:
                raise JournalError(
                    f"record {record.seq}: a journal must start with a session record"
                )
            fmt = record.data.get("format")
            if fmt != FORMAT:
                raise JournalError(
                    f"record {record.seq}: journal format {fmt!r}, this odohil reads {FORMAT}"
                )
            validate_header(record.data, f"record {record.seq}")
            try:
                header = decode(record.kind, record.data)
            except ValueError as exc:
                raise JournalError(f"record {record.seq}: {exc}") from None
            assert isinstance(header, SessionHeader)
            state = SessionState(header=header, plan=header.plan, n_records=1)
            continue
        state = apply(state, record)
    if state is None:
        raise JournalError("the journal holds no records")
    return state


def measures() -> tuple[str, ...]:
    """The measurement sources a session header may name: the wizard's
    operator and every pose source (the ``odohil.pose_sources`` plug-ins of
    odohil/session/plugins.py), sorted."""
    return tuple(sorted({OPERATOR, *plugins.names(plugins.POSE_SOURCES)}))


_SETTING_TYPES: dict[str, tuple[type, ...]] = {
    "port": (str,),
    "truth_socket": (str,),
    "trial_file": (str,),
    "baud": (int,),
    "seed": (int,),
    "mocap_url": (str,),
}


def validate_header(data: Mapping[str, Any], where: str = "session record") -> None:
    """Check the session record's members before anything uses them (a member
    may be absent: a session record needs only its format; :func:`description_of_header`
    refuses a header without ``robot_toml``).

    Raises:
        JournalError: naming the member and what it must be (a CRC-valid
            journal can still carry a header another program wrote).
    """

    def bad(member: str, what: str, value: Any) -> JournalError:
        return JournalError(f"{where}: {member} must be {what}, got {value!r}"[:500])

    protocol = None
    if "robot_toml" in data:
        toml = data["robot_toml"]
        if not isinstance(toml, str):
            raise bad("robot_toml", "the robot description's TOML text", toml)
        try:
            protocol = parse_robot_description(toml, "robot_toml").robot.protocol
        except OdohilError as exc:
            raise JournalError(f"{where}: {exc}") from None
    robot_path = data.get("robot_path")
    if robot_path is not None and not isinstance(robot_path, str):
        raise bad("robot_path", "a path (text)", robot_path)
    measure = data.get("measure")
    if "measure" in data and measure not in (known := measures()):
        raise bad("measure", f"one of {', '.join(known)}", measure)
    if "plan" in data:
        plan = data["plan"]
        if not isinstance(plan, dict):
            raise bad("plan", 'an object {"designs": [...]}', plan)
        try:
            check_session_plan(Plan.from_json(plan), protocol)
        except ParameterError as exc:
            raise JournalError(f"{where}: bad plan: {exc}") from None
    settings = data.get("settings", {})
    if not isinstance(settings, dict):
        raise bad("settings", "an object", settings)
    for key, types in _SETTING_TYPES.items():
        value = settings.get(key)
        if value is None:
            continue
        if isinstance(value, bool) or not isinstance(value, types):
            raise bad(f"settings.{key}", types[0].__name__, value)
        if key == "mocap_url":
            try:
                parse_tcp_url(cast(str, value))
            except ParameterError as exc:
                raise JournalError(f"{where}: settings.mocap_url: {exc}") from None
        if key in ("baud", "seed"):
            try:
                RANGES[key].check(f"settings.{key}", cast(int, value))
            except ParameterError as exc:
                raise JournalError(f"{where}: {exc}") from None


def apply(state: SessionState, record: Record) -> SessionState:
    """The state after one more record (not the first, ``session``, record).

    Raises:
        JournalError: the record does not fit the state, or is malformed.
    """
    try:
        event = decode(record.kind, record.data)
    except ValueError as exc:
        if str(exc).startswith("unknown event kind"):
            raise JournalError(f"record {record.seq}: {exc}") from None
        raise JournalError(f"record {record.seq} ({record.kind}) is malformed: {exc}") from None
    return apply_event(state, event, record.seq)


def apply_event(state: SessionState, event: Event, seq: int) -> SessionState:
    """The state after one more event, journaled as record ``seq``.

    Raises:
        JournalError: the event does not fit the state (naming the record).
    """
    handler = _HANDLERS.get(type(event))
    if handler is None and isinstance(event, SourceEvent):
        handler = _source_reading
    if handler is None:
        raise JournalError(f"record {seq}: unknown event kind {event.KIND!r}")
    try:
        new = handler(state, event, seq)
    except ValueError as exc:
        raise JournalError(f"record {seq} ({event.KIND}) is malformed: {exc}") from None
    return replace(new, n_records=new.n_records + 1)


E = TypeVar("E", bound=Event)
_Handler = Callable[[SessionState, Any, int], SessionState]
_HANDLERS: dict[type[Event], _Handler] = {}


def _on(*kinds: type[E]) -> Callable[[Callable[[SessionState, E, int], SessionState]], _Handler]:
    """Register a handler of the events ``kinds``."""

    def register(handler: Callable[[SessionState, E, int], SessionState]) -> _Handler:
        for kind in kinds:
            _HANDLERS[kind] = handler
        return handler

    return register


@_on(RobotConnected, Resumed, TornRecordKept, Stopped, StopUnconfirmed, StartPoseChecked)
def _information(state: SessionState, event: Event, seq: int) -> SessionState:
    """Records for the reader: the state does not change."""
    return state


@_on(SessionHeader)
def _second_session(state: SessionState, event: SessionHeader, seq: int) -> SessionState:
    raise JournalError(f"record {seq}: a second session record")


@_on(PlanSet)
def _plan(state: SessionState, event: PlanSet, seq: int) -> SessionState:
    if state.plan is not None:
        raise JournalError(f"record {seq}: a second plan")
    return replace(state, plan=event.plan)


@_on(Estimate)
def _estimate(state: SessionState, event: Estimate, seq: int) -> SessionState:
    return replace(state, last_estimate=event)


@_on(Finished)
def _finished(state: SessionState, event: Finished, seq: int) -> SessionState:
    return replace(state, finished=True)


def _plan_of(state: SessionState, event: Event, seq: int) -> Plan:
    if state.plan is None:
        raise JournalError(f"record {seq}: {event.KIND} before the plan")
    return state.plan


@_on(TrialStart)
def _trial_start(state: SessionState, event: TrialStart, seq: int) -> SessionState:
    plan = _plan_of(state, event, seq)
    trial, attempt, design_index = event.trial, event.attempt, event.design
    if state.open_trial is not None:
        raise JournalError(
            f"record {seq}: trial {trial} starts while trial "
            f"{state.open_trial.trial} attempt {state.open_trial.attempt} is still open"
        )
    if trial in state.done_trials:
        raise JournalError(f"record {seq}: trial {trial} started again after it completed")
    if design_index != plan.design_index(trial):
        raise JournalError(
            f"record {seq}: trial {trial} runs design {design_index}, the plan says "
            f"{plan.design_index(trial)}"
        )
    if event.backward is not None and event.backward != driven_backward(plan.design_of(trial)):
        raise JournalError(
            f"record {seq}: trial {trial} was driven "
            f"{'backward' if event.backward else 'forward'}, the plan says "
            f"{plan.design_of(trial).label()}"
        )
    if attempt != state.next_attempt(trial):
        raise JournalError(
            f"record {seq}: attempt {attempt} of trial {trial}, expected "
            f"{state.next_attempt(trial)}"
        )
    opened = OpenTrial(
        trial=trial,
        attempt=attempt,
        design_index=design_index,
        phase=Phase.MARKED,
        start=dict(event.start),
    )
    attempts = {**state.attempts, trial: attempt}
    return replace(state, open_trial=opened, attempts=attempts)


@_on(MotionStart)
def _motion_start(state: SessionState, event: MotionStart, seq: int) -> SessionState:
    opened = _current(state, event, seq, Phase.MARKED)
    return replace(state, open_trial=replace(opened, phase=Phase.MOVING))


@_on(MotionDone)
def _motion_done(state: SessionState, event: MotionDone, seq: int) -> SessionState:
    opened = _current(state, event, seq, Phase.MOVING)
    measuring = replace(
        opened,
        phase=Phase.MEASURING,
        encoder_end_pose=event.encoder_end_pose,
        trajectory=event.trajectory,
        end=dict(event.end),
    )
    return replace(state, open_trial=measuring)


def _source_reading(state: SessionState, event: SourceEvent, seq: int) -> SessionState:
    """A pose source's reading, folded into the open attempt's own record."""
    opened = _current(state, event, seq, Phase.MEASURING)
    return replace(state, open_trial=replace(opened, readings=event.fold(opened.readings)))


@_on(Void)
def _void(state: SessionState, event: Void, seq: int) -> SessionState:
    _current(state, event, seq)
    return replace(state, open_trial=None, voided=state.voided + 1)


@_on(Solved)
def _solved(state: SessionState, event: Solved, seq: int) -> SessionState:
    opened = _current(state, event, seq, Phase.MEASURING)
    plan = _plan_of(state, event, seq)
    if opened.trial in state.done_trials:
        raise JournalError(f"record {seq}: trial {opened.trial} solved twice")
    assert opened.encoder_end_pose is not None
    done = CompletedTrial(
        trial=opened.trial,
        attempt=opened.attempt,
        design=plan.design_of(opened.trial),
        design_index=opened.design_index,
        encoder_end_pose=opened.encoder_end_pose,
        pose_change=event.pose_change,
        cov=event.cov,
        clear_cut=event.clear_cut,
        start=opened.start,
        end=opened.end,
        note=event.reason,
        seq=seq,
        ambiguous=bool(event.ambiguous),
        candidates=event.candidates or (),
        flag_reason=event.flag_reason or "",
        readings=opened.readings,
    )
    return replace(state, completed=(*state.completed, done), open_trial=None)


def _current(state: SessionState, event: Any, seq: int, phase: Phase | None = None) -> OpenTrial:
    """The open attempt ``event`` (with its ``trial`` and ``attempt``) belongs
    to, in ``phase`` when given."""
    _plan_of(state, event, seq)
    opened = state.open_trial
    trial, attempt = event.trial, event.attempt
    if opened is None or (opened.trial, opened.attempt) != (trial, attempt):
        raise JournalError(
            f"record {seq}: {event.KIND} for trial {trial} attempt {attempt}, "
            "which is not the open trial"
        )
    if phase is not None and opened.phase is not phase:
        raise JournalError(
            f"record {seq}: {event.KIND} while trial {opened.trial} is "
            f"{opened.phase.value}, not {phase.value}"
        )
    return opened


def session_trials(state: SessionState, source: str = "session") -> TrialSet:
    """The completed forth-and-back trials as a trial set (raw-marks kind), in
    completion order (a general path's trials are :func:`session_path_trials`').

    Each trial's ``line`` is the journal line of its ``solved`` record;
    ``flagged``/``note`` say when the source was not sure of the pose, or
    flagged the trial (the tape: the slip check doubts it). Ambiguous trials
    are left out of ``trials`` and listed in ``ambiguous``.
    """
    description = description_of_header(state)
    line = [t for t in state.completed if isinstance(t.design, Design)]
    as_trials = [
        Trial(
            design=cast(Design, t.design),
            pose_change=np.array(t.pose_change, dtype=np.float64),
            pose_cov=np.array(t.cov, dtype=np.float64),
            marks=t.readings.marks(description) if t.readings is not None else None,
            odometry_end_pose=np.array(t.encoder_end_pose, dtype=np.float64),
            flagged=not t.clear_cut or bool(t.flag_reason),
            note="; ".join(part for part in (t.note, t.flag_reason) if part),
            line=t.seq,
            number=t.trial,
        )
        for t in line
    ]
    used = tuple(x for x, t in zip(as_trials, line, strict=True) if not t.ambiguous)
    left_out = tuple(x for x, t in zip(as_trials, line, strict=True) if t.ambiguous)
    return TrialSet(trials=used, kind="marks", source=source, ambiguous=left_out)


def session_path_trials(state: SessionState, source: str = "session") -> list[PathTrial]:
    """Every completed, unambiguous trial as a general-path trial (a
    forth-and-back trial as its design's encoder path), in completion order,
    numbered by its trial number, grouped for the model checks by design
    (a general path: its kind and direction; a forth-and-back design: its
    label).

    Each pose change is referred to the design's nominal encoder path: the
    encoders' departure from its nominal end pose (each leg and turn stops
    within the driver's tolerance of its target, and a robot's turns may stop
    short or long systematically) is taken off, to first order, as the
    predictive pose adds it (odohil/science/pose_selection.py); otherwise it
    would be read as a turn or distance error."""
    out = []
    for t in state.completed:
        if t.ambiguous:
            continue
        design = t.design
        departure = np.array(t.encoder_end_pose) - np.array(design.path().encoder_end_pose())
        departure[2] = wrap_angle(float(departure[2]))
        direction: Direction
        family: str
        if isinstance(design, PathDesign):
            family = design.kind
            direction = "ccw" if design.counter_clockwise else "cw"
        else:
            family = design.forward.label()  # one group a design, as the design recipe's
            direction = "mixed"
        out.append(
            PathTrial(
                path=design.path(),
                pose_change=np.array(t.pose_change, dtype=np.float64) - departure,
                measurement_cov=np.array(t.cov, dtype=np.float64),
                source=source,
                trial=t.trial,
                family=family,
                direction=direction,
            )
        )
    return out


def session_observations(state: SessionState) -> list[Observation]:
    """The completed trials as the estimators' observations (with the
    floor-mark covariance as measurement covariance)."""
    return trials_to_observations(session_trials(state))


def ambiguous_trials(state: SessionState) -> tuple[CompletedTrial, ...]:
    """The completed trials left out of every estimate because two candidate
    poses stayed plausible (for the verdict: "ambiguous trials left out")."""
    return tuple(t for t in state.completed if t.ambiguous)


def trials_to_observations(trials: TrialSet) -> list[Observation]:
    """Trials as observations; a trial without a covariance has an exact pose."""
    return [
        Observation(
            design=t.design,
            pose_change=t.pose_change,
            measurement_cov=t.pose_cov if t.pose_cov is not None else np.zeros((3, 3)),
            line=t.line,
            trial=t.number if t.number is not None else i + 1,
        )
        for i, t in enumerate(trials.trials)
    ]


@dataclass(frozen=True)
class LoadedSession:
    """A session read from its folder without changing it.

    Attributes:
        state: the replayed state.
        torn: the torn last record, if any (not used; say so to the user).
    """

    state: SessionState
    torn: TornRecord | None


def load_session(folder: str | Path) -> LoadedSession:
    """Read and replay a session folder (read-only).

    Raises:
        JournalError: no journal, or a corrupt or inconsistent one.
    """
    contents = read_journal(folder)
    return LoadedSession(replay(contents.records), contents.torn)


def load_session_trials(folder: str | Path) -> TrialSet:
    """The completed trials of a session folder, for offline estimation
    (``odohil estimate SESSION``). A torn last record is ignored, as on resume;
    call :func:`load_session` to report it.

    Raises:
        JournalError: no journal, or a corrupt or inconsistent one.
    """
    return session_trials(load_session(folder).state, source=str(folder))


def description_of_header(state: SessionState) -> RobotDescription:
    """The robot description journaled in the session header.

    Raises:
        JournalError: the header has no robot description.
    """
    toml = state.header.robot_toml
    if toml is None:
        raise JournalError("the session record holds no robot description (robot_toml)")
    return parse_robot_description(toml, state.header.robot_path or "session")
