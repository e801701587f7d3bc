"""Robot backends by name: the ``odohil.robots`` entry-point group.

The robot description's ``[robot] protocol`` names the backend (its default
is :data:`odohil.science.robot_description.DEFAULT_PROTOCOL`), the way
python-can picks a bus by its interface name; the port URL says where it is.
A backend is a class (or any object) with ``facts`` (its
:class:`~odohil.science.robot_facts.RobotFacts`: line speeds and default,
leg limits, whether its turns are exact, its ``[robot]`` keys and nominal
constants, its fake robot) and an ``open(url, baud, robot)`` that returns a
connected ``Robot`` (odohil/session/robots/protocol.py); ``robot`` is the description's
``[robot]`` table (:class:`RobotSettings`), which a backend uses or ignores. A
description's ``[serial] timeout_s`` (checked against the facts'
``reply_timeout_range_s`` when it is read) is handed to ``open`` as the keyword
``reply_timeout_s``, only when given: a backend's driver then waits that long for
each reply instead of its own default (``facts.reply_timeout_s``).
Another package adds a robot by declaring an entry point in the group;
nothing here names one, and nothing outside the backend knows its numbers:
the session and the CLI read them here (:func:`robot_facts`).

A backend with a fake robot for tests and demos declares it in
``facts.fake`` (:class:`~odohil.science.robot_facts.FakeFacts`): the pyserial
URL scheme its in-process fake serves (whose open port carries the true pose),
the client of a fake process's truth socket, and the emulator's and demo's
time scales. :func:`fake_hooks` is the one place that reads them.
"""

from __future__ import annotations

import dataclasses
import importlib
from collections.abc import Callable
from dataclasses import dataclass
from importlib.metadata import EntryPoint
from typing import Any, Protocol, cast

from odohil.errors import InitError, OdohilError, ParameterError, RobotDescriptionError
from odohil.science.limits import RANGES
from odohil.science.robot_description import (
    RobotDescription,
    RobotSettings,
    parse_robot_description,
)
from odohil.science.robot_facts import FakeFacts, RobotFacts
from odohil.session import plugins
from odohil.session.robots.protocol import Robot

ENTRY_POINT_GROUP = plugins.ROBOTS


class RobotBackend(Protocol):
    """What an ``odohil.robots`` entry point loads."""

    facts: RobotFacts
    """What the rest of odohil may know about the robot (line speeds, leg
    limits, turns, ``[robot]`` keys, its fake)."""

    def open(
        self,
        url: str,
        baud: int | None = None,
        robot: RobotSettings | None = None,
        *,
        reply_timeout_s: float | None = None,
    ) -> Robot:
        """Connect to the robot at ``url`` and check that it answers; ``robot``:
        the description's ``[robot]`` settings (None: the backend's defaults);
        ``reply_timeout_s``: how long its driver waits for a reply, s (None:
        its own default; passed only when the description gives one)."""
        ...


def clear_cache() -> None:
    """Forget the entry points found so far (a package installed since)."""
    plugins.clear_cache()


def _named(protocol: str) -> tuple[EntryPoint, ...]:
    return tuple(e for e in plugins.registered(ENTRY_POINT_GROUP) if e.name == protocol)


def backend_names() -> tuple[str, ...]:
    """The registered backend names, sorted."""
    return plugins.names(ENTRY_POINT_GROUP)


def find_backend(protocol: str) -> RobotBackend:
    """The backend registered as ``protocol``.

    Raises:
        RobotDescriptionError: none is registered under that name (the
            message lists the names that are).
        InitError: it is registered but cannot be loaded.
    """
    found = _named(protocol)
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
    protocol: str,
    url: str,
    baud: int | None = None,
    robot: RobotSettings | None = None,
    reply_timeout_s: float | None = None,
) -> Robot:
    """Connect through the backend named ``protocol`` at ``url`` (at ``baud``,
    or the backend's default when None), handing it the description's
    ``[robot]`` settings (None: the backend's defaults) and its reply timeout
    ``reply_timeout_s`` (s; None: the backend's own, and the keyword is not
    passed, so a backend that predates it still opens)."""
    backend = find_backend(protocol)
    if reply_timeout_s is None:
        return backend.open(url, baud, robot)
    facts = robot_facts(protocol)
    facts.check_reply_timeout(reply_timeout_s)  # the description was checked; a caller may not
    return backend.open(url, baud, robot, reply_timeout_s=reply_timeout_s)


def robot_facts(protocol: str) -> RobotFacts:
    """The facts the backend registered as ``protocol`` declares.

    Raises:
        RobotDescriptionError, InitError: as :func:`find_backend`; InitError
            also when what it declares is not a RobotFacts.
    """
    facts = find_backend(protocol).facts
    if not isinstance(facts, RobotFacts):
        raise InitError(f"robot backend {protocol!r} declares no RobotFacts (got {facts!r})")
    return facts


def known_facts(protocol: str) -> RobotFacts | None:
    """The facts of the backend ``protocol``; None when no backend of that
    name is installed (a recorded robot: a description read for its
    constants only). InitError when it is installed but cannot load."""
    if not _named(protocol):
        return None
    return robot_facts(protocol)


def parse_description(text: str, source: str = "robot description") -> RobotDescription:
    """A robot description parsed and checked against its backend's facts
    (:func:`odohil.science.robot_description.parse_robot_description` with
    :func:`known_facts`): ``[serial] baud`` one of its line speeds, only the
    ``[robot]`` keys it reads, its nominal constants and its ``turns_exact``
    as the defaults. RobotDescriptionError naming the key otherwise."""
    return parse_robot_description(text, source, facts=known_facts)


def check_leg(protocol: str | None, l_m: float, label: str = "l") -> float:
    """``l_m`` if the robot of ``protocol`` drives a leg that long (its
    facts' limits; with no installed backend, or None, the science caps:
    ``RANGES["l"]``); else ParameterError naming ``label`` and the range."""
    facts = None if protocol is None else known_facts(protocol)
    if facts is None:
        return RANGES["l"].check(label, l_m)
    return facts.check_leg(l_m, label)


def check_baud(protocol: str, baud: int, origin: str) -> int:
    """``baud`` if the backend ``protocol`` speaks it (checked before
    anything is sent), else ParameterError naming where it came from and the
    line speeds it speaks."""
    facts = robot_facts(protocol)
    if not facts.speaks(baud):
        raise ParameterError(
            f"baud {baud} ({origin}) is not one {protocol} speaks: give one of {facts.rates_text()}"
        )
    return baud


def _load(reference: str, what: str) -> Any:
    """The object ``"module:name"`` names (imported now); InitError if it cannot load."""
    module, _, name = reference.partition(":")
    try:
        return getattr(importlib.import_module(module), name)
    except (ImportError, AttributeError, ValueError) as exc:
        raise InitError(f"the fake's {what} {reference} cannot load: {exc}") from exc


@dataclass(frozen=True)
class FakeHooks(FakeFacts):
    """What a backend declares about its fake robot (its
    :class:`~odohil.science.robot_facts.FakeFacts`), with the loaders of the
    code it names (the fakes are imported only when asked for)."""

    def truth_client_class(self) -> Any:
        """The truth client's class (constructed with the socket path;
        ``open()``, ``close()`` and ``true_pose()``).

        Raises:
            InitError: it cannot be imported.
        """
        return _load(self.truth_client, "truth client")

    def emulator_function(self) -> Any:
        """The function ``odohil emulate`` calls with a
        ``fakes.launch.EmulateOptions`` to serve the fake on a pty.

        Raises:
            InitError: the backend names none, or it cannot be imported.
        """
        if not self.emulator:
            raise InitError(f"the fake of {self.url_scheme} declares no emulator")
        return _load(self.emulator, "emulator")


def fake_hooks(protocol: str) -> FakeHooks | None:
    """The fake robot the backend ``protocol`` declares (None: it has none).

    Raises:
        RobotDescriptionError, InitError: as :func:`robot_facts`.
    """
    fake = robot_facts(protocol).fake
    if fake is None:
        return None
    return FakeHooks(**dataclasses.asdict(fake))


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


def emulated_backends() -> tuple[RobotFacts, ...]:
    """The facts of every registered backend that declares a fake robot for
    ``odohil emulate`` (a backend that cannot load is left out)."""
    found = []
    for name in backend_names():
        try:
            facts = robot_facts(name)
        except OdohilError:
            continue
        if facts.fake is not None and facts.fake.emulator:
            found.append(facts)
    return tuple(found)


@dataclass(frozen=True)
class EmulateHelp:
    """What ``odohil emulate --help`` says of its robot-dependent options, from
    the facts of the backends with a fake (:func:`emulated_backends`).

    Attributes:
        robot: ``--robot``: which fakes there are.
        time_scale: ``--time-scale``: each fake's default time scale.
        baud: ``--baud``: each fake's default line rate (its backend's default baud).
    """

    robot: str
    time_scale: str
    baud: str


def emulate_help() -> EmulateHelp:
    """The help of ``odohil emulate``'s ``--robot``, ``--time-scale`` and ``--baud``."""
    backends = emulated_backends()
    names = ", ".join(f"{f.name} (the {f.label})" for f in backends) or "none installed"

    def defaults(what: str, value: Callable[[RobotFacts], float]) -> str:
        per_robot = ", ".join(f"{f.name} {value(f):g}" for f in backends)
        return f"default: the robot's own {what} ({per_robot})"

    scale = defaults("time scale", lambda f: f.fake.emulate_time_scale if f.fake else 1.0)
    return EmulateHelp(
        f"Which fake robot: {names}, or a robot description file whose "
        "\\[robot] protocol is one of them.",
        f"Simulated seconds per wall second (motion, zr, timestamp); {scale}.",
        "Line rate (pacing and the pty speed); "
        + defaults("line rate, its backend's default baud", lambda f: f.default_baud)
        + ".",
    )


def emulator(protocol: str) -> tuple[RobotFacts, FakeHooks, Any]:
    """The facts, the fake and the emulator function (which ``odohil emulate``
    calls to serve the fake on a pty) of the backend ``protocol``.

    Raises:
        RobotDescriptionError, InitError: no such backend, or it declares no
            fake robot to emulate, or the emulator cannot be imported.
    """
    facts, hooks = robot_facts(protocol), fake_hooks(protocol)
    if hooks is None or not hooks.emulator:
        raise InitError(f"the {protocol} backend declares no fake robot to emulate")
    return facts, hooks, hooks.emulator_function()


def emulated_line(
    facts: RobotFacts, hooks: FakeHooks, baud: int | None, time_scale: float | None
) -> tuple[int, float]:
    """``odohil emulate``'s line rate (baud) and time scale (simulated seconds
    per wall second): those given, else the backend's default baud and its
    fake's default time scale.

    Raises:
        ParameterError: a baud rate the robot does not speak.
    """
    if baud is not None and not facts.speaks(baud):
        raise ParameterError(f"the {facts.label} speaks {facts.rates_text()} baud, got {baud}")
    scale = hooks.emulate_time_scale if time_scale is None else time_scale
    return (facts.default_baud if baud is None else baud), scale
