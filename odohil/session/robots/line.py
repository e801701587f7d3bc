"""Which robot, port and baud a session uses, and where each value came from.

The command line wins, then a resumed session's journal (what it used), then
the robot description (``[serial] port`` and ``baud``), then the backend's
default baud. The backend is the description's ``[robot] protocol``. The
banner of ``run``, ``wizard`` and ``resume`` prints :meth:`Line.describe`.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from typing import Any

from odohil.errors import InitError, ParameterError
from odohil.science.robot_description import RobotDescription, RobotSettings
from odohil.session.robots.registry import check_baud, fake_hooks, robot_facts


@dataclass(frozen=True)
class Line:
    """The connection in force.

    Attributes:
        protocol: the robot backend's name (``[robot] protocol``).
        port: the port URL; port_from: where it came from.
        baud: the line speed; baud_from: where it came from.
        robot: the description's ``[robot]`` settings, handed to the backend
            (its kinematic constants).
        timeout_s: the description's ``[serial] timeout_s``, the driver's
            reply timeout, s; None when not given (the backend's own).
    """

    protocol: str
    port: str
    port_from: str
    baud: int
    baud_from: str
    robot: RobotSettings | None = None
    timeout_s: float | None = None

    def describe(self) -> str:
        """E.g. ``PROTOCOL on /dev/ttyUSB0 (--port) at 9600 baud (robot.toml [serial])``."""
        return (
            f"{self.protocol} on {self.port} ({self.port_from}) "
            f"at {self.baud} baud ({self.baud_from})"
        )

    def to_json(self) -> dict[str, Any]:
        """For the journal's settings."""
        return {"port": self.port, "baud": self.baud}


def _first(candidates: Iterator[tuple[Any, str]]) -> tuple[Any, str] | None:
    for value, origin in candidates:
        if value is not None:
            return value, origin
    return None


def resolve_line(
    description: RobotDescription,
    port: str | None,
    baud: int | None,
    robot_path: str = "robot.toml",
    journaled: Mapping[str, Any] | None = None,
) -> Line:
    """The connection in force (see the module docstring).

    Raises:
        ParameterError: no port anywhere (names --port and ``[serial] port``),
            or a baud the backend does not speak (its facts' ``baud_rates``).
        RobotDescriptionError: the robot description names no installed backend.
    """
    serial = description.serial
    where = f"{robot_path} [serial]"
    old = journaled or {}
    found_port = _first(
        iter(
            [
                (port, "--port"),
                (old.get("port"), "the session's journal"),
                (serial.port if "port" in serial.given else None, where),
            ]
        )
    )
    if found_port is None:
        raise ParameterError(
            f"no port: give --port (a device, pty or pyserial URL) or set port in the "
            f"[serial] table of {robot_path}"
        )
    facts = robot_facts(description.robot.protocol)
    found_baud = _first(
        iter(
            [
                (baud, "--baud"),
                (old.get("baud"), "the session's journal"),
                (serial.baud if "baud" in serial.given else None, where),
                (facts.default_baud, f"{description.robot.protocol} default"),
            ]
        )
    )
    assert found_baud is not None
    check_baud(description.robot.protocol, int(found_baud[0]), found_baud[1])  # before sending
    return Line(
        description.robot.protocol,
        str(found_port[0]),
        found_port[1],
        int(found_baud[0]),
        found_baud[1],
        description.robot,
        serial.timeout_s if "timeout_s" in serial.given else None,
    )


def carries_truth(line: Line) -> bool:
    """Whether ``line``'s port is its backend's in-process fake, whose open
    port carries the true pose (the backend declares the scheme:
    odohil/session/robots/registry.py ``fake_hooks``)."""
    hooks = fake_hooks(line.protocol)
    return hooks is not None and line.port.startswith(hooks.url_scheme)


def truth_available(line: Line, truth_socket: str | None) -> bool:
    """Whether ``--measure fake`` can read the fake's true pose: a truth
    socket is given, or the port is the backend's in-process fake."""
    return bool(truth_socket) or carries_truth(line)


def open_truth_client(line: Line, truth_socket: str) -> Any:
    """The open client of a fake process's truth socket, of the kind the
    line's backend declares (``true_pose()``, ``snapshot()``, ``close()``).

    Raises:
        InitError: the backend declares no fake robot, or the socket cannot be opened.
    """
    hooks = fake_hooks(line.protocol)
    if hooks is None:
        raise InitError(
            f"--truth-socket: the {line.protocol} backend declares no fake robot with a "
            "truth side channel"
        )
    client = hooks.truth_client_class()(truth_socket)
    client.open()
    return client
