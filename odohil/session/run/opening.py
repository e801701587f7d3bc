"""Open a prepared session: the motion-capture stream, the session's lock, the
robot (through the backend registry) with the fake's truth side channel, and
the session's journal; everything closed on exit, the robot stopped.

Order: a resumed session is locked before the robot's port opens (a second
run on it sends nothing), but its ``resumed`` record is journaled only once
the robot has answered, so a resume whose port does not open or whose robot
does not answer leaves the journal's records as they were (only a torn last
record kept aside is journaled then: that repair of the file did happen;
odohil/session/run/engine.py ``open_to_resume``); a new session is created
only once the robot has answered, so a failure before leaves no folder behind. Each step that fails
raises :class:`~odohil.session.run.checks.PreflightFailed` naming it.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any, TypeVar

from odohil.errors import OdohilError, ParameterError
from odohil.session.journal.file import Journal, TornRecord
from odohil.session.journal.state import SessionState
from odohil.session.measure.protocol import PoseSource
from odohil.session.measure.registry import Connection, OpenContext, OpenedSource, open_measure
from odohil.session.robots.line import Line, open_truth_client
from odohil.session.robots.protocol import Robot
from odohil.session.robots.registry import open_robot
from odohil.session.run.checks import ExitClass, PreflightCheck, PreflightFailed, Prepared
from odohil.session.run.engine import journal_resumed, open_to_resume, start_session
from odohil.session.run.measure_option import journal_name
from odohil.session.run.start_pose import pose_text, sample_pose

T = TypeVar("T")
CheckSeen = Callable[[PreflightCheck], None]
"""Told each check as it passes (the wizard's ticks)."""


@dataclass(frozen=True)
class Opened:
    """An open session.

    Attributes:
        prepared: what pre-flight found.
        journal: the session's journal (locked, open for appending).
        state: the session as journaled.
        robot: the connected robot; truth: the fake's truth side channel (None if none).
        source: the pose source (None for the operator's: the wizard builds it).
        torn: a resumed journal's torn last record, kept aside (None if none).
    """

    prepared: Prepared
    journal: Journal
    state: SessionState
    robot: Robot
    truth: Any
    source: PoseSource | None
    torn: TornRecord | None = None


def _ignore(check: PreflightCheck) -> None:
    pass


def _step(name: str, run: Callable[[], T], exit_class: ExitClass = "bad input") -> T:
    """``run()``; a failure raises PreflightFailed naming step ``name``, of
    ``exit_class``, except a ParameterError, which is always bad input (a
    value the user gave, such as a port URL option its handler refuses:
    odohil/driver/port.py)."""
    try:
        return run()
    except ParameterError as exc:
        raise PreflightFailed(PreflightCheck(name, False, str(exc), "bad input")) from exc
    except (OdohilError, OSError) as exc:
        raise PreflightFailed(PreflightCheck(name, False, str(exc), exit_class)) from exc


@contextlib.contextmanager
def connect(line: Line, truth_socket: str | None) -> Iterator[tuple[Robot, Any]]:
    """The robot on ``line`` (through the backend its protocol names) and its
    truth side channel (None when there is none).

    A backend's in-process fake port (``fakerobot://``, ``fakecreate2://``;
    its URL handler registered by the caller) carries its own truth (on the
    backend's ``transport``, the open port); a pty fake robot needs
    ``truth_socket``, read by the client its backend declares
    (odohil/session/robots/registry.py ``fake_hooks``). The robot is closed (stopped) on exit.
    """
    robot = open_robot(line.protocol, line.port, line.baud, line.robot, line.timeout_s)
    transport = robot.transport
    truth: Any = None
    try:
        if truth_socket:
            truth = open_truth_client(line, truth_socket)
        elif hasattr(transport, "truth"):
            truth = transport
        yield robot, truth
    finally:
        try:
            robot.close()
        finally:
            if truth is not None and hasattr(truth, "close") and truth is not transport:
                truth.close()


@contextlib.contextmanager
def open_session(prepared: Prepared, seen: CheckSeen = _ignore) -> Iterator[Opened]:
    """Open ``prepared`` (module docstring); ``seen`` is told each step that passes."""
    spec, line = prepared.spec, prepared.line
    with contextlib.ExitStack() as stack:
        option = prepared.option
        measuring: OpenedSource | None = None
        if option is not None:
            context = OpenContext(prepared.description, prepared.seed)
            measuring = _step(
                "measurement", lambda: stack.enter_context(open_measure(option, context)), "error"
            )
            if measuring.note:
                seen(PreflightCheck("measurement", True, measuring.note))
        torn = None
        resuming = None
        if prepared.resumed is not None:
            resuming = _step("session", lambda: open_to_resume(spec.folder))
            stack.enter_context(resuming.journal)
            journal, torn = resuming.journal, resuming.torn
            assert resuming.state.plan is not None
            seen(PreflightCheck("session", True, f"resuming {spec.folder}"))
        robot, truth = _step(
            "robot answers",
            lambda: stack.enter_context(connect(line, prepared.truth_socket)),
            "error",
        )
        sample = _step("robot answers", robot.odometry, "error")
        moving = "MOVING (it will be stopped first)" if sample.moving else "standing still"
        encoders = f"{line.describe()}; encoders {pose_text(sample_pose(sample))}, {moving}"
        seen(PreflightCheck("robot answers", True, encoders))
        if resuming is not None:
            opened = resuming
            state = _step("session", lambda: journal_resumed(opened, spec.note).state, "error")
        else:
            journal, state = _step("session", lambda: _start(prepared))
            stack.enter_context(journal)
            seen(PreflightCheck("session", True, f"new session in {spec.folder}"))
        source = None if measuring is None else measuring.make(Connection(robot, truth))
        yield Opened(prepared, journal, state, robot, truth, source, torn)


def _start(prepared: Prepared) -> tuple[Journal, SessionState]:
    return start_session(
        prepared.spec.folder,
        prepared.toml,
        prepared.plan,
        measure=journal_name(prepared.option),
        settings=prepared.settings,
        robot_path=prepared.robot_path,
    )
