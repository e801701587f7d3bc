"""Load a robot description (TOML) from disk."""

from __future__ import annotations

from pathlib import Path

from odohil.errors import OdohilError, RobotDescriptionError
from odohil.science.robot_description import RobotDescription
from odohil.session.bounded_io import MIB, read_file_text
from odohil.session.robots import parse_description as parse_robot_description

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
