"""Load a robot description (TOML) from disk."""

from __future__ import annotations

from pathlib import Path

from odohil.errors import RobotDescriptionError
from odohil.science.robot_description import RobotDescription, parse_robot_description


def load_robot_description(path: str | Path) -> RobotDescription:
    """Read and validate the robot description at ``path`` (UTF-8 TOML).

    Raises:
        RobotDescriptionError: the file cannot be read, or its content is invalid;
            the message starts with the path.
    """
    file = Path(path)
    try:
        text = file.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise RobotDescriptionError(f"cannot read robot description {file}: {exc}") from exc
    return parse_robot_description(text, source=str(file))
