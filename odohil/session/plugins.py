"""Plug-ins by name: the entry-point groups and the built-in ones, as strings.

A plug-in is named ``"module:attr"`` and imported only when it is asked for
(python-can's ``BACKENDS`` and can/_entry_points.py): the built-in ones in
:data:`BUILTIN`, other packages' through their installed entry points. So a
registry never imports its own built-ins, and nothing here imports one.
The entry points found are cached while ``sys.path`` stays the same
(reading every installed distribution's metadata costs tens of
milliseconds): :func:`clear_cache` forgets them.
"""

from __future__ import annotations

import functools
import importlib
import sys
from importlib.metadata import EntryPoint, entry_points
from typing import Any

ROBOTS = "odohil.robots"
"""Robot backends (the robot description's ``[robot] protocol``)."""

POSE_SOURCES = "odohil.pose_sources"
"""Pose-source kinds (``--measure``)."""

BUILTIN: dict[str, dict[str, str]] = {
    POSE_SOURCES: {
        "fake": "odohil.session.measure.kinds:FAKE",
        "file": "odohil.session.measure.kinds:TRIAL_FILE",
        "tcp": "odohil.session.measure.kinds:MOTION_CAPTURE",
    },
}
"""The built-in plug-ins of each group, by name: there also in a source
checkout without installed metadata, and not replaceable by an entry point."""


@functools.lru_cache(maxsize=8)
def _registered(group: str, search_path: tuple[str, ...]) -> tuple[EntryPoint, ...]:
    return tuple(sorted(entry_points(group=group), key=lambda e: e.name))


def registered(group: str) -> tuple[EntryPoint, ...]:
    """The installed entry points of ``group`` on today's ``sys.path``, by name."""
    return _registered(group, tuple(sys.path))


def clear_cache() -> None:
    """Forget the entry points found so far (a package installed since)."""
    _registered.cache_clear()


def builtin(group: str) -> dict[str, str]:
    """The built-in plug-ins of ``group``: name -> ``"module:attr"``."""
    return dict(BUILTIN.get(group, {}))


def targets(group: str) -> dict[str, str]:
    """Every plug-in of ``group``: name -> ``"module:attr"``, the built-in
    ones first (an entry point cannot replace one), sorted by name."""
    found = builtin(group)
    for entry in registered(group):
        found.setdefault(entry.name, entry.value)
    return dict(sorted(found.items()))


def names(group: str) -> tuple[str, ...]:
    """The names of every plug-in of ``group`` (built-in and registered),
    sorted, without loading one."""
    return tuple(targets(group))


def load_target(target: str) -> Any:
    """The object ``"module:attr"`` names (``attr`` may be dotted; an entry
    point's ``[extras]`` are ignored).

    Raises:
        ImportError: the module cannot be imported.
        AttributeError: it has no such attribute.
    """
    module, _, attr = target.split("[")[0].strip().partition(":")
    loaded: Any = importlib.import_module(module)
    for part in attr.split(".") if attr else ():
        loaded = getattr(loaded, part)
    return loaded
