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

A backend with a fake robot for tests and demos declares it (optional):
``fake_url_scheme`` (the pyserial URL scheme its in-process fake serves,
whose open port carries the true pose) and ``fake_truth_client``
(``"module:Class"`` of the client that reads a fake process's truth socket).
:func:`fake_hooks` is the one place that reads them.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass
from importlib.metadata import entry_points
from typing import Any, Protocol, cast

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


@dataclass(frozen=True)
class FakeHooks:
    """What a backend declares about its fake robot.

    Attributes:
        url_scheme: the pyserial URL scheme of its in-process fake (e.g.
            ``fakerobot:``); a port of that scheme carries its own truth.
        truth_client: ``"module:Class"`` of the client of a fake process's
            truth socket (constructed with the socket path; ``open()``,
            ``close()`` and ``true_pose()``).
    """

    url_scheme: str
    truth_client: str

    def truth_client_class(self) -> Any:
        """The truth client's class (imported now).

        Raises:
            InitError: it cannot be imported.
        """
        module, _, name = self.truth_client.partition(":")
        try:
            return getattr(importlib.import_module(module), name)
        except (ImportError, AttributeError) as exc:
            raise InitError(
                f"the fake's truth client {self.truth_client} cannot load: {exc}"
            ) from exc


def fake_hooks(protocol: str) -> FakeHooks | None:
    """The fake robot the backend ``protocol`` declares (None: it has none).

    Raises:
        RobotDescriptionError, InitError: as :func:`find_backend`.
    """
    backend = find_backend(protocol)
    scheme = getattr(backend, "fake_url_scheme", None)
    client = getattr(backend, "fake_truth_client", None)
    if not isinstance(scheme, str) or not isinstance(client, str):
        return None
    return FakeHooks(scheme, client)


def fake_url_schemes() -> tuple[str, ...]:
    """The URL schemes of every registered backend's in-process fake."""
    schemes = []
    for name in backend_names():
        try:
            hooks = fake_hooks(name)
        except InitError:
            continue
        if hooks is not None:
            schemes.append(hooks.url_scheme)
    return tuple(schemes)
