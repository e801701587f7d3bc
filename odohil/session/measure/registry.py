"""Pose sources by name: the ``odohil.pose_sources`` entry-point group.

``--measure TEXT`` names where a trial's real pose change comes from (the
:class:`~odohil.session.measure.protocol.PoseSource` protocol). Each kind of source
is one object, registered under its name the way robot backends are
(odohil/session/robots/registry.py, the ``odohil.robots`` group). It declares:

- ``name`` (str): the kind, as journaled in the session header's ``measure``;
- ``forms`` (str): its ``--measure`` forms in words, for help and errors
  (e.g. ``tcp://HOST:PORT (a motion-capture stream)``);
- ``parse(text)``: its typed, frozen settings when ``text`` is one of its
  forms, else None (a ParameterError naming ``--measure`` when ``text`` is
  its form but malformed);
- ``journal_settings(settings)``: the members it adds to the header's
  ``settings`` (JSON), and ``from_journal(settings)``: its settings back from
  them (a resumed session);
- ``check(settings, preflight)``: its pre-flight check (a :class:`Preflight`):
  nothing moves and nothing is written; raises an OdohilError naming the
  option, file or field;
- ``open(settings, ctx)``: a context manager entered before the session is
  journaled and the robot's port opened (an :class:`OpenContext`); it opens
  what the source reads (a motion-capture stream, its first pose required)
  and yields an :class:`OpenedSource`, whose ``make`` builds the PoseSource
  once the robot is connected (a :class:`Connection`: the robot and the
  fake's truth channel). Leaving it closes what it opened;
- optionally ``floor_marks`` (bool, default False): the source solves poses
  from floor-mark distances, so the description's cross distances must tell
  the plan's designs apart; and ``fallback`` (bool, default False): its
  ``parse`` is asked only after every other kind's (the trial file's, which
  takes a path).

The built-in kinds (odohil/session/measure/kinds.py: ``fake``, ``file``,
``tcp``, named by string in odohil/session/plugins.py) are always there,
also in a source checkout without installed metadata; another package adds
a kind by declaring an entry point in the group (``toy = "toy_module:TOY"``:
an object with the members above, or a class whose instances have them).
Nothing here names a kind. The entry points found are cached while
``sys.path`` stays the same (:func:`clear_cache`).
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterator, Mapping
from contextlib import AbstractContextManager
from dataclasses import dataclass, field
from typing import Any, Protocol, cast

from odohil.errors import InitError, ParameterError
from odohil.science.robot_description import RobotDescription
from odohil.session import plugins
from odohil.session.measure.protocol import PoseSource
from odohil.session.plans.plan import Plan
from odohil.session.robots.protocol import Robot

ENTRY_POINT_GROUP = plugins.POSE_SOURCES


@dataclass(frozen=True)
class Preflight:
    """What a kind's pre-flight check may look at (nothing moves, nothing is written).

    Attributes:
        description: the robot description.
        plan: the session's plan.
        truth_available: whether the fake robot's true pose can be read (a
            truth socket is given or the port is a backend's in-process fake).
    """

    description: RobotDescription
    plan: Plan
    truth_available: bool


@dataclass(frozen=True)
class OpenContext:
    """What a kind's opener gets besides its settings.

    Attributes:
        description: the robot description.
        seed: the session's seed (simulated noise).
    """

    description: RobotDescription
    seed: int


@dataclass(frozen=True)
class Connection:
    """The open connection a PoseSource is made for.

    Attributes:
        robot: the connected robot.
        truth: the fake robot's truth channel (``truth()`` or ``snapshot()``
            giving ``true_x_m``, ``true_y_m``, ``true_theta_rad``), None when
            there is none.
    """

    robot: Robot
    truth: Any = None


@dataclass(frozen=True)
class OpenedSource:
    """What a kind's opener yields.

    Attributes:
        make: the PoseSource for the open connection.
        note: what to tell the user once the source is ready ("" for nothing),
            e.g. ``motion capture tcp://...: poses arriving``.
    """

    make: Callable[[Connection], PoseSource]
    note: str = ""


class PoseSourceKind(Protocol):
    """What an ``odohil.pose_sources`` entry point loads (see the module docstring)."""

    @property
    def name(self) -> str:
        """The kind, as journaled in the session header's ``measure``."""
        ...

    @property
    def forms(self) -> str:
        """The ``--measure`` forms it takes, in words."""
        ...

    def parse(self, text: str) -> Any:
        """Its settings when ``text`` is its form, else None."""
        ...

    def journal_settings(self, settings: Any) -> dict[str, Any]:
        """The header's ``settings`` members of ``settings`` (JSON)."""
        ...

    def from_journal(self, journaled: Mapping[str, Any]) -> Any:
        """Its settings from a header's ``settings``."""
        ...

    def check(self, settings: Any, preflight: Preflight) -> None:
        """Its pre-flight check; raises an OdohilError."""
        ...

    def open(self, settings: Any, ctx: OpenContext) -> AbstractContextManager[OpenedSource]:
        """Open what the source reads; yields its :class:`OpenedSource`."""
        ...


def clear_cache() -> None:
    """Forget the entry points found so far (a package installed since)."""
    plugins.clear_cache()


def _load(name: str, target: str) -> PoseSourceKind:
    try:
        loaded = plugins.load_target(target)
    except (ImportError, AttributeError) as exc:
        raise InitError(f"pose source {name!r} ({target}) cannot load: {exc}") from exc
    kind = cast(PoseSourceKind, loaded() if isinstance(loaded, type) else loaded)
    if kind.name != name:
        raise InitError(f"pose source {name!r} ({target}) calls itself {kind.name!r}")
    return kind


def kinds() -> dict[str, PoseSourceKind]:
    """Every kind by name: the built-in ones and those registered in the
    group (an entry point cannot replace a built-in one).

    Raises:
        InitError: a kind cannot be loaded (it is named).
    """
    return {
        name: _load(name, target) for name, target in plugins.targets(ENTRY_POINT_GROUP).items()
    }


def kind_names() -> tuple[str, ...]:
    """The names of every pose source (built-in and registered), sorted,
    without loading one."""
    return plugins.names(ENTRY_POINT_GROUP)


def accepted_forms() -> str:
    """Every ``--measure`` form, in words (the fallback kinds last)."""
    return "; ".join(kind.forms for kind in _in_parse_order(kinds()))


def find_kind(name: str, where: str = "the session's measure") -> PoseSourceKind:
    """The pose source called ``name``.

    Raises:
        ParameterError: none is (the message names ``where`` and the installed ones).
        InitError: a registered kind cannot be loaded.
    """
    found = kinds()
    if name not in found:
        raise ParameterError(
            f"no pose source {name!r} ({where}); installed: {', '.join(sorted(found))}"
        )
    return found[name]


def _in_parse_order(found: Mapping[str, PoseSourceKind]) -> list[PoseSourceKind]:
    every = [found[name] for name in sorted(found)]
    return [k for k in every if not fallback(k)] + [k for k in every if fallback(k)]


def floor_marks(kind: PoseSourceKind) -> bool:
    """Whether ``kind`` solves poses from floor-mark distances (default False)."""
    return bool(getattr(kind, "floor_marks", False))


def fallback(kind: PoseSourceKind) -> bool:
    """Whether ``kind``'s parse is asked after the others' (default False)."""
    return bool(getattr(kind, "fallback", False))


@dataclass(frozen=True)
class MeasureOption:
    """What ``--measure`` (or a resumed session's header) names.

    Attributes:
        kind: the pose source's name, as journaled in the header's ``measure``.
        settings: its typed, frozen settings.
        text: ``--measure`` as given ("" when read back from a journal).
    """

    kind: str
    settings: Any = field(default=None)
    text: str = ""

    def source_kind(self) -> PoseSourceKind:
        """The pose source it names."""
        return find_kind(self.kind, f"--measure {self.text}" if self.text else "the session")

    @property
    def floor_marks(self) -> bool:
        """Its poses come from floor-mark distances (the tape's cross
        distances must tell the plan's designs apart)."""
        return floor_marks(self.source_kind())

    def journal_settings(self) -> dict[str, Any]:
        """The members it adds to the session header's ``settings``."""
        return self.source_kind().journal_settings(self.settings)


OPERATOR_WORDS = frozenset({"tape", "operator", "wizard", "manual"})
"""``--measure`` words a user may try for the operator's tape, which only the
wizard asks for: none is a pose source (unless a file of that name exists)."""


def parse_measure(text: str) -> MeasureOption:
    """``--measure TEXT``: the first kind whose ``parse`` takes it (fallback kinds last).

    Raises:
        ParameterError: no kind takes it (the message names --measure and
            every accepted form), or its kind finds it malformed.
        InitError: a registered kind cannot be loaded.
    """
    found = kinds()
    for kind in _in_parse_order(found):
        settings = kind.parse(text)
        if settings is not None:
            return MeasureOption(kind.name, settings, text)
    forms = "; ".join(k.forms for k in _in_parse_order(found))
    operator = (
        "; the operator's tape is measured in the wizard: `odohil wizard` to calibrate, "
        "`odohil wizard --validate SESSION --path PATH` to validate"
        if text.lower() in OPERATOR_WORDS
        else ""
    )
    raise ParameterError(
        f"--measure {text!r}: no pose source takes this form{operator}; give one of: {forms}"
    )


def journaled_measure(measure: str | None, settings: Mapping[str, Any]) -> MeasureOption:
    """The pose source a session header names (its ``measure``), with its
    settings from the header's ``settings``.

    Raises:
        ParameterError: no such pose source is installed, or its settings are
            missing from the header.
    """
    kind = find_kind(str(measure), "the session's measure")
    return MeasureOption(str(measure), kind.from_journal(dict(settings)))


def check_measure(option: MeasureOption, preflight: Preflight) -> None:
    """The kind's pre-flight check of ``option`` (nothing moves, nothing is written)."""
    option.source_kind().check(option.settings, preflight)


@contextlib.contextmanager
def open_measure(option: MeasureOption, ctx: OpenContext) -> Iterator[OpenedSource]:
    """Open the pose source ``option`` names (before the session is journaled
    and the port opened); closed on exit."""
    with option.source_kind().open(option.settings, ctx) as opened:
        yield opened
