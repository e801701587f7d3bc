"""Load a robot description (TOML) from disk; find a built-in one by name."""

from __future__ import annotations

from importlib.resources import files
from pathlib import Path

from odohil.errors import OdohilError, RobotDescriptionError
from odohil.science.robot_description import RobotDescription
from odohil.session.bounded_io import MIB, read_file_text
from odohil.session.robots.registry import parse_description as parse_robot_description

MAX_DESCRIPTION_BYTES = 1 * MIB
"""Largest robot description file, bytes (a real one is about 1 KiB)."""


def read_robot_toml(
    path: str | Path, error: type[OdohilError] = RobotDescriptionError, what: str = ""
) -> str:
    """The text of the robot description at ``path``: a regular UTF-8 file of at
    most :data:`MAX_DESCRIPTION_BYTES` (odohil/session/bounded_io.py).

    Args:
        path: the file.
        error: the error class raised.
        what: how messages name the file (default ``robot description``).

    Raises:
        error: the file cannot be read, is not a regular file or is too large.
    """
    return read_file_text(
        path,
        what=what or "robot description",
        max_bytes=MAX_DESCRIPTION_BYTES,
        error=error,
    )


def load_robot_description(path: str | Path) -> RobotDescription:
    """Read and validate the robot description at ``path`` (UTF-8 TOML).

    Raises:
        RobotDescriptionError: the file cannot be read, or its content is invalid;
            the message starts with the path.
    """
    file = Path(path)
    return parse_robot_description(read_robot_toml(file), source=str(file))


BUILTIN_PACKAGE = "odohil.robots"
"""The package whose top-level ``*.toml`` files are the built-in descriptions."""


def builtin_names() -> tuple[str, ...]:
    """The built-in descriptions' names, sorted (the package's top-level
    ``*.toml`` files; data sets' robots in its ``datasets/`` are not ``--robot``s)."""
    return tuple(
        sorted(
            entry.name.removesuffix(".toml")
            for entry in files(BUILTIN_PACKAGE).iterdir()
            if entry.name.endswith(".toml") and entry.is_file()
        )
    )


def builtin_path(name: str) -> Path:
    """The file of the built-in description ``name`` (one of :func:`builtin_names`)."""
    return Path(str(files(BUILTIN_PACKAGE).joinpath(f"{name}.toml")))


def resolve_robot(value: str | Path) -> Path:
    """The description file ``value`` names: itself when it is a file, else the
    built-in description of that name (a file of that name wins).

    Raises:
        RobotDescriptionError: neither (the message names the value and the
            built-in names).
    """
    path = Path(value)
    if path.is_file():
        return path
    names = builtin_names()
    if str(value) in names:
        return builtin_path(str(value))
    raise RobotDescriptionError(
        f"cannot read {str(value)!r}: no such robot description file, and not the name "
        f"of a built-in description ({', '.join(names)})"
    )


def robot_protocol(value: str | Path) -> str:
    """The ``[robot] protocol`` of the description ``value`` names (a file or
    a built-in name): which fake robot ``demo`` and ``emulate`` start.

    Raises:
        RobotDescriptionError: no such file or built-in name, or a file that
            is not a valid robot description.
    """
    return load_robot_description(resolve_robot(value)).robot.protocol
