"""The events of a session journal, and the session state they replay to.

Event kinds, in the order a session writes them (``data`` members in brackets):

- ``session`` (always record 1, written whole so that a session always has
  its plan): format, robot description TOML text, the measurement source,
  settings, plan [``format``, ``robot_toml``, ``robot_path``, ``measure``,
  ``settings``, ``plan``: the :meth:`Plan.to_json` object];
- ``plan``: the plan, for a session record without one;
- ``robot``: identity and settings of the robot, after each connect;
- ``resumed``: a later process took the session over;
- ``torn_record``: the torn last record found on resume was kept aside
  [``file``, ``bytes``, ``reason``];
- ``trial_start``: the robot was re-zeroed and the start marks made
  [``trial``, ``attempt``, ``design``, ``backward``: driven with every leg
  reversed (one-way trials alternate), ``start``: the source's start data];
- ``motion_start`` [``trial``, ``attempt``];
- ``motion_done``: the motion finished [``trial``, ``attempt``,
  ``encoder_end_pose`` (x m, y m, theta rad), ``trajectory`` (rows t s, x m,
  y m, theta rad), ``end``: the source's end data];
- ``measurement``: one distance [``trial``, ``attempt``, ``index``, ``label``,
  ``value_m``];
- ``measurements_rejected``: the distances of this attempt are discarded and
  taken again [``trial``, ``attempt``, ``reason``];
- ``remeasured``: the slip check doubted the trial's pose; the suspect
  distance was taken again, or the operator kept it [``trial``, ``attempt``,
  ``index``, ``label``, ``reason``, ``previous_m``, ``value_m`` (null when
  kept), ``kept``]; a kept value flags the trial;
- ``extra_distance``: an ambiguous trial's extra cross distance, asked for
  by name [``trial``, ``attempt``, ``start``, ``end`` (screw names),
  ``label``, ``value_m``];
- ``solved``: the pose change; the trial is complete [``trial``, ``attempt``,
  ``pose_change``, ``cov``, ``chi2``, ``clear_cut``, ``reason``, and
  optionally ``ambiguous`` (two candidate poses stay plausible: the trial is
  left out of every estimate), ``candidates`` (their poses), ``slip`` (why
  the slip check, or the per-trial check of odohil/session/plausibility.py,
  doubts the trial), ``check`` (that check's numbers: ``T``, ``limit``, the
  measured and encoder distances from the start)];
- ``estimate`` [``n_trials``, ``result``: the estimate's JSON object];
- ``void``: the attempt is discarded and the trial redone [``trial``,
  ``attempt``, ``reason``];
- ``stopped``: the process stopped early and the robot reported that it
  stopped [``reason``, ``message``, ``robot``, ``state``: the encoder sample];
- ``stop_unconfirmed``: the process stopped early and the robot did NOT
  report that it stopped: it may have driven on [``reason``, ``message``,
  ``detail``];
- ``finished`` [``n_trials``].

A trial is identified by its number in the plan (1-based); each try at it is
an attempt (1, 2, ...). A trial counts once it has a ``solved`` record, and a
second ``solved`` for the same trial is a :class:`JournalError`.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field, replace
from enum import Enum
from pathlib import Path
from typing import Any, cast

import numpy as np

from odohil.errors import JournalError, OdohilError, ParameterError
from odohil.science.estimators import Observation
from odohil.science.floor_marks import MarkDistances
from odohil.science.limits import RANGES
from odohil.science.paths import Design
from odohil.science.robot_description import RobotDescription
from odohil.session.journal import Record, TornRecord, read_journal
from odohil.session.mocap.stream import parse_tcp_url
from odohil.session.plan import Plan, check_session_plan
from odohil.session.robots import parse_description as parse_robot_description
from odohil.session.trial_files import Trial, TrialSet

FORMAT = 1
"""Version of the journal's event schema."""

SESSION = "session"
PLAN = "plan"
ROBOT = "robot"
RESUMED = "resumed"
TORN_RECORD = "torn_record"
TRIAL_START = "trial_start"
MOTION_START = "motion_start"
MOTION_DONE = "motion_done"
MEASUREMENT = "measurement"
MEASUREMENTS_REJECTED = "measurements_rejected"
REMEASURED = "remeasured"
EXTRA_DISTANCE = "extra_distance"
SOLVED = "solved"
ESTIMATE = "estimate"
VOID = "void"
STOPPED = "stopped"
STOP_UNCONFIRMED = "stop_unconfirmed"
FINISHED = "finished"
START_POSE = "start_pose"

_INFO_KINDS = frozenset({ROBOT, RESUMED, TORN_RECORD, STOPPED, STOP_UNCONFIRMED, START_POSE})


class Phase(Enum):
    """Where an open (not yet solved) trial attempt stands."""

    MARKED = "marked"
    """Re-zeroed and start marks made; the motion was not started."""
    MOVING = "moving"
    """The motion was started and did not report its end."""
    MEASURING = "measuring"
    """The motion finished; distances are being taken (maybe all are in)."""


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
        end: the measurement source's end-mark data once the motion is done.
        measurements: the distances taken so far, metres, in order.
        rejections: how many times this attempt's distances were rejected.
        remeasures: how many suspect distances were taken again.
        slip: why the slip check doubts the trial, when the operator kept the
            suspect value (empty otherwise).
        extra: extra cross distances (start screw, end screw, metres) taken
            to settle an ambiguous choice.
    """

    trial: int
    attempt: int
    design_index: int
    phase: Phase
    start: Mapping[str, Any]
    encoder_end_pose: tuple[float, float, float] | None = None
    trajectory: tuple[tuple[float, ...], ...] = ()
    end: Mapping[str, Any] = field(default_factory=dict)
    measurements: tuple[float, ...] = ()
    rejections: int = 0
    remeasures: int = 0
    slip: str = ""
    extra: tuple[tuple[str, str, float], ...] = ()


@dataclass(frozen=True)
class CompletedTrial:
    """A trial with its solved pose change.

    Attributes:
        trial: trial number in the plan (1-based).
        attempt: the attempt that completed it.
        design: its design.
        design_index: index of the design in the plan.
        encoder_end_pose: (x m, y m, theta rad) the encoders reported.
        measurements: the floor-mark distances, metres (same-screw then cross).
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
        slip: why the slip check doubts the trial (empty when it does not).
    """

    trial: int
    attempt: int
    design: Design
    design_index: int
    encoder_end_pose: tuple[float, float, float]
    measurements: tuple[float, ...]
    pose_change: tuple[float, float, float]
    cov: tuple[tuple[float, float, float], ...]
    clear_cut: bool
    start: Mapping[str, Any]
    end: Mapping[str, Any]
    note: str = ""
    seq: int = 0
    ambiguous: bool = False
    candidates: tuple[tuple[float, float, float], ...] = ()
    slip: str = ""


@dataclass(frozen=True)
class SessionState:
    """A session as its journal tells it.

    Attributes:
        header: the ``session`` record's data.
        plan: the plan, once journaled.
        completed: completed trials, in completion order.
        open_trial: the attempt under way, if any.
        voided: number of voided attempts.
        last_estimate: the data of the latest ``estimate`` record.
        finished: whether a ``finished`` record closes the session.
        n_records: number of records replayed.
    """

    header: Mapping[str, Any]
    plan: Plan | None = None
    completed: tuple[CompletedTrial, ...] = ()
    open_trial: OpenTrial | None = None
    voided: int = 0
    attempts: Mapping[int, int] = field(default_factory=dict)
    last_estimate: Mapping[str, Any] | None = None
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
            plan = None
            if "plan" in record.data:
                try:
                    plan = Plan.from_json(record.data["plan"])
                except ParameterError as exc:
                    raise JournalError(f"record {record.seq}: bad plan: {exc}") from None
            state = SessionState(header=record.data, plan=plan, n_records=1)
            continue
        state = apply(state, record)
    if state is None:
        raise JournalError("the journal holds no records")
    return state


MEASURES = ("fake", "file", "operator", "tcp")
"""The measurement sources a session header may name."""
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
    if "measure" in data and measure not in MEASURES:
        raise bad("measure", f"one of {', '.join(MEASURES)}", measure)
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
        JournalError: the record does not fit the state.
    """
    try:
        new = _apply(state, record)
    except (KeyError, TypeError, ValueError, IndexError) as exc:
        if isinstance(exc, JournalError):
            raise
        raise JournalError(f"record {record.seq} ({record.kind}) is malformed: {exc!r}") from None
    return replace(new, n_records=new.n_records + 1)


def _apply(state: SessionState, record: Record) -> SessionState:
    kind, data = record.kind, record.data
    if kind in _INFO_KINDS:
        return state
    if kind == SESSION:
        raise JournalError(f"record {record.seq}: a second session record")
    if kind == PLAN:
        if state.plan is not None:
            raise JournalError(f"record {record.seq}: a second plan")
        try:
            return replace(state, plan=Plan.from_json(data))
        except ParameterError as exc:
            raise JournalError(f"record {record.seq}: bad plan: {exc}") from None
    if kind == ESTIMATE:
        return replace(state, last_estimate=data)
    if kind == FINISHED:
        return replace(state, finished=True)
    if state.plan is None:
        raise JournalError(f"record {record.seq}: {kind} before the plan")
    if kind == TRIAL_START:
        return _trial_start(state, record, state.plan)
    opened = _current(state, record)
    if kind == MOTION_START:
        _expect(opened, record, Phase.MARKED)
        return replace(state, open_trial=replace(opened, phase=Phase.MOVING))
    if kind == MOTION_DONE:
        _expect(opened, record, Phase.MOVING)
        pose = _triple(data["encoder_end_pose"])
        trajectory = tuple(tuple(float(v) for v in row) for row in data.get("trajectory", []))
        return replace(
            state,
            open_trial=replace(
                opened,
                phase=Phase.MEASURING,
                encoder_end_pose=pose,
                trajectory=trajectory,
                end=dict(data.get("end", {})),
            ),
        )
    if kind == MEASUREMENT:
        _expect(opened, record, Phase.MEASURING)
        if int(data["index"]) != len(opened.measurements):
            raise JournalError(
                f"record {record.seq}: measurement {data['index']} where "
                f"{len(opened.measurements)} was expected"
            )
        value = float(data["value_m"])
        return replace(
            state, open_trial=replace(opened, measurements=(*opened.measurements, value))
        )
    if kind == MEASUREMENTS_REJECTED:
        _expect(opened, record, Phase.MEASURING)
        return replace(
            state,
            open_trial=replace(opened, measurements=(), rejections=opened.rejections + 1, extra=()),
        )
    if kind == REMEASURED:
        _expect(opened, record, Phase.MEASURING)
        index = int(data["index"])
        if not 0 <= index < len(opened.measurements):
            raise JournalError(f"record {record.seq}: re-measured distance {index} was not taken")
        if bool(data["kept"]):
            return replace(state, open_trial=replace(opened, slip=str(data["reason"])))
        values = list(opened.measurements)
        values[index] = float(data["value_m"])
        return replace(
            state,
            open_trial=replace(
                opened, measurements=tuple(values), remeasures=opened.remeasures + 1
            ),
        )
    if kind == EXTRA_DISTANCE:
        _expect(opened, record, Phase.MEASURING)
        extra = (str(data["start"]), str(data["end"]), float(data["value_m"]))
        return replace(state, open_trial=replace(opened, extra=(*opened.extra, extra)))
    if kind == VOID:
        return replace(state, open_trial=None, voided=state.voided + 1)
    if kind == SOLVED:
        _expect(opened, record, Phase.MEASURING)
        if opened.trial in state.done_trials:
            raise JournalError(f"record {record.seq}: trial {opened.trial} solved twice")
        assert opened.encoder_end_pose is not None
        cov = tuple(_triple(row) for row in data["cov"])
        if len(cov) != 3:
            raise ValueError("cov must be 3x3")
        done = CompletedTrial(
            trial=opened.trial,
            attempt=opened.attempt,
            design=state.plan.design_of(opened.trial),
            design_index=opened.design_index,
            encoder_end_pose=opened.encoder_end_pose,
            measurements=opened.measurements,
            pose_change=_triple(data["pose_change"]),
            cov=cov,
            clear_cut=bool(data["clear_cut"]),
            start=opened.start,
            end=opened.end,
            note=str(data.get("reason", "")),
            seq=record.seq,
            ambiguous=bool(data.get("ambiguous", False)),
            candidates=tuple(_triple(c) for c in data.get("candidates", [])),
            slip=str(data.get("slip", "")),
        )
        return replace(state, completed=(*state.completed, done), open_trial=None)
    raise JournalError(f"record {record.seq}: unknown event kind {kind!r}")


def _trial_start(state: SessionState, record: Record, plan: Plan) -> SessionState:
    data = record.data
    if state.open_trial is not None:
        raise JournalError(
            f"record {record.seq}: trial {data.get('trial')} starts while trial "
            f"{state.open_trial.trial} attempt {state.open_trial.attempt} is still open"
        )
    trial, attempt, design_index = int(data["trial"]), int(data["attempt"]), int(data["design"])
    if trial in state.done_trials:
        raise JournalError(f"record {record.seq}: trial {trial} started again after it completed")
    if design_index != plan.design_index(trial):
        raise JournalError(
            f"record {record.seq}: trial {trial} runs design {design_index}, the plan says "
            f"{plan.design_index(trial)}"
        )
    if "backward" in data and bool(data["backward"]) != plan.design_of(trial).backward:
        raise JournalError(
            f"record {record.seq}: trial {trial} was driven "
            f"{'backward' if data.get('backward') else 'forward'}, the plan says "
            f"{plan.design_of(trial).label()}"
        )
    if attempt != state.next_attempt(trial):
        raise JournalError(
            f"record {record.seq}: attempt {attempt} of trial {trial}, expected "
            f"{state.next_attempt(trial)}"
        )
    opened = OpenTrial(
        trial=trial,
        attempt=attempt,
        design_index=design_index,
        phase=Phase.MARKED,
        start=dict(data.get("start", {})),
    )
    attempts = {**state.attempts, trial: attempt}
    return replace(state, open_trial=opened, attempts=attempts)


def _current(state: SessionState, record: Record) -> OpenTrial:
    opened = state.open_trial
    trial, attempt = int(record.data["trial"]), int(record.data["attempt"])
    if opened is None or (opened.trial, opened.attempt) != (trial, attempt):
        raise JournalError(
            f"record {record.seq}: {record.kind} for trial {trial} attempt {attempt}, "
            "which is not the open trial"
        )
    return opened


def _expect(opened: OpenTrial, record: Record, phase: Phase) -> None:
    if opened.phase is not phase:
        raise JournalError(
            f"record {record.seq}: {record.kind} while trial {opened.trial} is "
            f"{opened.phase.value}, not {phase.value}"
        )


def _triple(value: Any) -> tuple[float, float, float]:
    x, y, z = (float(v) for v in value)
    return (x, y, z)


def session_trials(state: SessionState, source: str = "session") -> TrialSet:
    """The completed trials as a trial set (raw-marks kind), in completion order.

    Each trial's ``line`` is the journal line of its ``solved`` record;
    ``flagged``/``note`` say when the floor-mark solution was not clear-cut or
    the slip check doubts it. Ambiguous trials are left out of ``trials`` and
    listed in ``ambiguous``.
    """
    description = description_of_header(state)
    as_trials = [
        Trial(
            design=t.design,
            pose_change=np.array(t.pose_change, dtype=np.float64),
            pose_cov=np.array(t.cov, dtype=np.float64),
            marks=MarkDistances.of(description, t.measurements)
            if t.measurements
            else None,  # measured as a pose (a trial file of poses, motion capture)
            odometry_end_pose=np.array(t.encoder_end_pose, dtype=np.float64),
            flagged=not t.clear_cut or bool(t.slip),
            note="; ".join(part for part in (t.note, t.slip) if part),
            line=t.seq,
            number=t.trial,
        )
        for t in state.completed
    ]
    used = tuple(x for x, t in zip(as_trials, state.completed, strict=True) if not t.ambiguous)
    left_out = tuple(x for x, t in zip(as_trials, state.completed, strict=True) if t.ambiguous)
    return TrialSet(trials=used, kind="marks", source=source, ambiguous=left_out)


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
    if not isinstance(state.header.get("robot_toml"), str):
        raise JournalError("the session record holds no robot description (robot_toml)")
    return parse_robot_description(
        str(state.header["robot_toml"]), str(state.header.get("robot_path") or "session")
    )
