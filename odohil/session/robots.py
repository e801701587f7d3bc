"""Robot backends by name: the ``odohil.robots`` entry-point group.

The robot description's ``[robot] protocol`` names the backend (its default
is :data:`odohil.science.robot_description.DEFAULT_PROTOCOL`), the way
python-can picks a bus by its interface name; the port URL says where it is.
A backend is a class (or any object) with a ``default_baud`` (int), optionally
``baud_rates`` (the line speeds it accepts, checked before anything is sent),
and an ``open(url, baud, robot)`` that returns a connected ``Robot``
(odohil/session/robot.py); ``robot`` is the description's ``[robot]`` table
(:class:`RobotSettings`: its constants), which a backend uses or ignores.
Another package adds a robot by declaring an entry point in the group;
nothing here names one.
"""

from __future__ import annotations

from importlib.metadata import entry_points
from typing import Protocol, cast

from odohil.errors import InitError, RobotDescriptionError
from odohil.science.robot_description import RobotSettings
from odohil.session.robot import Robot

ENTRY_POINT_GROUP = "odohil.robots"


class RobotBackend(Protocol):
    """What an ``odohil.robots`` entry point loads."""

    default_baud: int
    """The line speed used when neither the command line nor the file gives one."""

    def open(self, url: str, baud: int | None = None, robot: RobotSettings | None = None) -> Robot:
        """Connect to the robot at ``url`` and check that it answers; ``robot``:
        the description's ``[robot]`` settings (None: the backend's defaults)."""
        ...


def backend_names() -> tuple[str, ...]:
    """The registered backend names, sorted."""
    return tuple(sorted(ep.name for ep in entry_points(group=ENTRY_POINT_GROUP)))


def find_backend(protocol: str) -> RobotBackend:
    """The backend registered as ``protocol``.

    Raises:
        RobotDescriptionError: none is registered under that name (the
            message lists the names that are).
        InitError: it is registered but cannot be loaded.
    """
    found = entry_points(group=ENTRY_POINT_GROUP, name=protocol)
    if not found:
        known = ", ".join(backend_names()) or "none"
        raise RobotDescriptionError(
            f"no robot backend {protocol!r} ([robot] protocol in the robot description); "
            f"installed: {known}"
        )
    entry = next(iter(found))
    try:
        return cast(RobotBackend, entry.load())
    except (ImportError, AttributeError) as exc:
        raise InitError(f"robot backend {protocol!r} ({entry.value}) cannot load: {exc}") from exc


def open_robot(
    protocol: str, url: str, baud: int | None = None, robot: RobotSettings | None = None
) -> Robot:
    """Connect through the backend named ``protocol`` at ``url`` (at ``baud``,
    or the backend's default when None), handing it the description's
    ``[robot]`` settings (None: the backend's defaults)."""
    return find_backend(protocol).open(url, baud, robot)
