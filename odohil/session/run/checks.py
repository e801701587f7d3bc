"""The one ordered list of pre-flight checks, made before anything is written
or moved: each a :class:`PreflightCheck` (the wizard shows them as ticks; run,
resume, demo and validate report the first failure). The list stops at its
first failure: a later check needs what the earlier ones found.

Order: session folder, robot description, session (a resumed one's plan),
plan feasible, plan estimable, trials per design, exclusions, cross
distances, floor space, port, measurement. The checks themselves are those
of odohil/session/plans/ (checks.py, plan.py) and odohil/session/robots/line.py.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal, TypeVar

from odohil import units
from odohil.errors import InitError, JournalError, OdohilError, ParameterError
from odohil.science.path_estimability import Estimability
from odohil.science.pose_selection import check_redundancy
from odohil.science.robot_description import RobotDescription
from odohil.session.journal.file import Journal, journal_path
from odohil.session.journal.state import SessionState, description_of_header, load_session
from odohil.session.plans.checks import (
    check_estimable,
    check_floor,
    check_trials_per_design,
    check_turns,
    default_variant,
    turn_warning,
)
from odohil.session.plans.plan import Plan, check_session_plan, parse_plan
from odohil.session.results.outcome import check_exclude
from odohil.session.robots.description import read_robot_toml
from odohil.session.robots.line import Line, resolve_line, truth_available
from odohil.session.robots.registry import parse_description as parse_robot_description
from odohil.session.run import measure_option as measure
from odohil.session.run.measure_option import OPERATOR, MeasureOption
from odohil.session.run.spec import SessionSpec

ExitClass = Literal["bad input", "error"]
"""What a failed check means for the exit status (odohil/cli/exit_codes.py):
``bad input`` (an option, file or session that cannot be used) or ``error``
(something that should have answered did not); either way nothing moved."""
T = TypeVar("T")


@dataclass(frozen=True)
class PreflightCheck:
    """One pre-flight check and how it came out.

    Attributes:
        name: what was checked (``plan feasible``, ``port``...).
        passed: whether it passed.
        message: what was found, or why it failed (naming the option or file
            and what is accepted).
        exit_class: what a failure means (:data:`ExitClass`).
    """

    name: str
    passed: bool
    message: str
    exit_class: ExitClass = "bad input"


class PreflightFailed(InitError):
    """A pre-flight check failed (before or while the session opens): nothing moved."""

    def __init__(self, check: PreflightCheck) -> None:
        super().__init__(f"{check.name}: {check.message}")
        self.check = check


@dataclass(frozen=True)
class Prepared:
    """A session that passed pre-flight: what it will use.

    Attributes:
        spec: as given.
        description: the robot description; toml: its text; robot_path: its file.
        plan: the plan; line: the port, baud and backend in force.
        option: the measurement; seed: the tape's seed; truth_socket: the fake's.
        settings: the header's settings of a new session, or what a resumed
            run connects with.
        resumed: the journaled state of a session to resume (read, not yet
            locked), None for a new one.
        warnings: what passed but deserves a word (turn designs allowed).
    """

    spec: SessionSpec
    description: RobotDescription
    toml: str
    robot_path: str
    plan: Plan
    line: Line
    option: MeasureOption | None
    seed: int
    truth_socket: str | None
    settings: Mapping[str, Any]
    resumed: SessionState | None = None
    warnings: tuple[str, ...] = field(default_factory=tuple)


@dataclass(frozen=True)
class Preflight:
    """The checks made, in order (up to the first failure), and the session
    they prepared (None when one failed)."""

    checks: tuple[PreflightCheck, ...]
    prepared: Prepared | None

    @property
    def failure(self) -> PreflightCheck | None:
        """The failed check (the last made), or None when all passed."""
        return next((c for c in self.checks if not c.passed), None)


class _Stop(Exception):
    pass


class _List:
    """The checks as they are made."""

    def __init__(self) -> None:
        self.checks: list[PreflightCheck] = []

    def check(self, name: str, run: Callable[[], T], detail: Callable[[T], str]) -> T:
        """Record ``run()``'s outcome under ``name``; an OdohilError or OSError
        it raises is the failure (and ends the list)."""
        try:
            value = run()
        except (OdohilError, OSError) as exc:
            self.checks.append(PreflightCheck(name, False, str(exc)))
            raise _Stop from None
        self.checks.append(PreflightCheck(name, True, detail(value)))
        return value

    def fail(self, name: str, message: str) -> None:
        self.checks.append(PreflightCheck(name, False, message))
        raise _Stop


def check_session_folder(session: Path | None) -> None:
    """A ``--session`` that exists must be a folder, and a symbolic link must
    lead somewhere (ParameterError otherwise)."""
    if session is not None and session.is_symlink() and not session.exists():
        raise ParameterError(
            f"--session {session} is a symbolic link to {os.readlink(session)}, which does "
            "not exist: create that folder, or give another --session"
        )
    if session is not None and session.exists() and not session.is_dir():
        raise ParameterError(
            f"--session {session} is a file, not a session folder: give a new or "
            "existing session folder"
        )


def preflight(spec: SessionSpec) -> Preflight:
    """Run the checks of ``spec`` in order (module docstring); nothing is
    written, no port opened."""
    done = _List()
    try:
        prepared = _prepare(spec, done)
    except _Stop:
        return Preflight(tuple(done.checks), None)
    return Preflight(tuple(done.checks), prepared)


def require(result: Preflight) -> Prepared:
    """The prepared session, or :class:`PreflightFailed` of the first failure."""
    if result.prepared is None:
        failure = result.failure
        assert failure is not None
        raise PreflightFailed(failure)
    return result.prepared


def _prepare(spec: SessionSpec, done: _List) -> Prepared:
    folder = spec.folder
    exists = journal_path(folder).exists() or journal_path(folder).is_symlink()
    done.check("session folder", lambda: _folder(spec, exists), lambda _: str(folder))
    resumed = spec.mode == "resume" or (exists and spec.mode == "auto")
    state = done.check("session", lambda: _load(folder), _progress) if resumed else None
    description, toml, robot_path = done.check(
        "robot description", lambda: _description(spec, state), lambda d: d[2] or "the session's"
    )
    old = dict(_header(state).get("settings", {}))
    try:  # checked in its place, last ("measurement"); until then a bad form counts as a tape
        option = measure.measure_option(spec.measure, _header(state).get("measure"), old)
        bad_measure: OdohilError | None = None
    except OdohilError as exc:
        option, bad_measure = None, exc
    if state is not None and _header(state).get("measure") == OPERATOR != spec.measure:
        done.fail(
            "session",
            f"{folder} is a wizard session (the operator measures): continue it with "
            f"`odohil wizard --port PORT --session {folder}`",
        )
    plan = done.check("plan feasible", lambda: _plan(spec, state, description), _plan_text)
    calibrate = spec.purpose == "calibrate" and state is None
    if calibrate:
        done.check("plan estimable", lambda: check_estimable(plan, description), _estimable)
        if not spec.allow_few_trials:
            done.check("trials per design", lambda: check_trials_per_design(plan, False), _few)
        done.check(
            "exclusions",
            lambda: check_exclude(spec.exclude, range(1, plan.n_trials + 1)),
            lambda _: ", ".join(map(str, sorted(spec.exclude))) or "none",
        )
    if option is None or option.floor_marks:  # the cross distances must tell the designs apart
        done.check(
            "cross distances",
            lambda: check_redundancy(description, [d for d, _ in plan.line_items]),
            lambda _: "enough for every design",
        )
    done.check(
        "floor space", lambda: check_floor(plan, description), lambda _: _floor(plan, description)
    )
    line = done.check(
        "port",
        lambda: resolve_line(
            description, spec.port, spec.baud, robot_path or "robot.toml", old or None
        ),
        lambda found: found.describe(),
    )
    socket = spec.truth_socket or old.get("truth_socket")
    done.check(
        "measurement",
        lambda: _measurement(option, description, plan, line, socket, bad_measure),
        str,
    )
    seed = spec.seed if spec.seed is not None else int(old.get("seed") or 0)
    settings = {
        **old,
        **line.to_json(),
        "truth_socket": socket,
        "seed": seed,
        **measure.settings_of(option, old, spec.measure is not None),
        **spec.settings,
    }
    warning = turn_warning(plan, description) if spec.purpose == "calibrate" else None
    warnings = () if warning is None else (warning,)
    return Prepared(
        spec, description, toml, robot_path, plan, line, option, seed, socket, settings, state,
        warnings,
    )  # fmt: skip


def _header(state: SessionState | None) -> Mapping[str, Any]:
    if state is None:
        return {}
    return {"measure": state.header.measure, "settings": state.header.settings}


def _load(folder: Path) -> SessionState:
    """A session to resume, read (not locked): JournalError when it cannot be."""
    path = journal_path(folder)
    if not (path.exists() or path.is_symlink()):
        raise JournalError(
            f"cannot open the session journal in {folder}: it holds no journal.jsonl "
            "(nothing to resume)"
        )
    Journal.check_not_in_use(folder)  # a running odohil's: "session in use"
    state = load_session(folder).state
    if state.finished:
        raise JournalError(f"the session in {folder} is finished; nothing to resume")
    if state.plan is None:
        raise JournalError(f"the session in {folder} has no plan")
    return state


def _folder(spec: SessionSpec, exists: bool) -> None:
    check_session_folder(spec.folder)
    if spec.mode == "new" and exists:
        Journal.check_not_in_use(spec.folder)  # a running odohil's: "session in use"
        raise ParameterError(
            f"--session {spec.folder} already holds a session journal; use "
            f"`odohil resume {spec.folder}` to continue it, or give another --session"
        )


def _progress(state: SessionState) -> str:
    plan = state.plan
    n = 0 if plan is None else plan.n_trials
    return f"{len(state.completed)} of {units.plural(n, 'trial')} done"


def _description(
    spec: SessionSpec, state: SessionState | None
) -> tuple[RobotDescription, str, str]:
    if state is not None:
        return (
            description_of_header(state),
            str(state.header.robot_toml),
            state.header.robot_path or "",
        )
    path = "" if spec.robot_path is None else str(spec.robot_path)
    if spec.robot_toml is not None:
        return (
            parse_robot_description(spec.robot_toml, path or "robot description"),
            spec.robot_toml,
            path,
        )
    if spec.robot_path is None:
        raise ParameterError("a new session needs --robot FILE (its robot description)")
    toml = read_robot_toml(spec.robot_path, what="--robot: robot description")
    return parse_robot_description(toml, source=path), toml, path


def _plan(spec: SessionSpec, state: SessionState | None, description: RobotDescription) -> Plan:
    if state is not None and spec.plan is None:
        assert state.plan is not None
        return state.plan
    if isinstance(spec.plan, Plan):
        plan = spec.plan
    else:
        text = spec.plan or spec.default_plan or ""
        if not text:
            raise ParameterError("no plan: give --plan (e.g. k=1,l=6,n=30;k=20,l=0.5,n=30)")
        try:
            plan = parse_plan(text, default_variant(description))
        except ParameterError as exc:
            raise ParameterError(f"--plan: {exc}") from None
    if state is not None:
        assert state.plan is not None
        if plan.to_text() != state.plan.to_text():
            raise ParameterError(
                f"--plan {spec.plan if isinstance(spec.plan, str) else plan.to_text()} differs "
                f"from the session's plan ({state.plan.to_text()}) in {spec.folder}: give no "
                "--plan (or that one) to resume it, or another --session for a new session"
            )
        return state.plan
    try:
        plan = check_session_plan(plan, description.robot.protocol)
    except ParameterError as exc:
        raise ParameterError(f"--plan: {exc}") from None
    if spec.max_leg_m is not None:
        long = [
            i.design.label()
            for i in plan.items
            if max(i.design.path().legs.length_m) > spec.max_leg_m
        ]
        if long:
            raise ParameterError(
                f"--plan: legs of {', '.join(long)} exceed --max-leg-m {spec.max_leg_m:g} m "
                "(the longest leg the floor allows)"
            )
    if spec.purpose == "calibrate":
        check_turns(plan, description, spec.allow_turns)
    return plan


def _plan_text(plan: Plan) -> str:
    return (
        f"{units.plural(plan.n_trials, 'trial')}, {plan.distance_m:.1f} m of driving "
        f"({plan.to_text()})"
    )


def _estimable(statement: Estimability | None) -> str:
    if statement is None:
        return "its trials can identify the four parameters"
    return statement.text()


def _few(_: None) -> str:
    return "enough trials a design for honest intervals"


def _floor(plan: Plan, description: RobotDescription) -> str:
    given = description.floor_length_m
    limit = f"of {given:g} m" if given is not None else "(no [floor] length_m given)"
    return f"the plan needs {plan.excursion_m:g} m of floor {limit}"


def _measurement(
    option: MeasureOption | None,
    description: RobotDescription,
    plan: Plan,
    line: Line,
    truth_socket: str | None,
    bad: OdohilError | None,
) -> str:
    if bad is not None:
        raise bad
    return measure.check(option, description, plan, truth_available(line, truth_socket))
