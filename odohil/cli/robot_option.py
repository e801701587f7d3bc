"""``--robot``: a robot description file, or the name of a built-in one
(odohil/session/robot_file.py finds it); anything else is a usage error
(exit 2) naming the option and the names."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import typer

from odohil.errors import OdohilError
from odohil.session.robot_file import builtin_names, resolve_robot
from odohil.session.robot_file import robot_protocol as protocol_of

ROBOT_HELP = f"Robot description (TOML file), or a built-in one: {', '.join(builtin_names())}."


def robot_callback(
    ctx: typer.Context, param: typer.CallbackParam, value: Path | None
) -> Path | None:
    """A typer callback for ``--robot``: the resolved file, or None when not given."""
    if value is None:
        return None
    try:
        return resolve_robot(value)
    except OdohilError as exc:
        raise typer.BadParameter(str(exc), param_hint=param.opts[0]) from None


def robot_option(help_tail: str = "") -> Any:
    """``--robot`` (:data:`ROBOT_HELP` and ``help_tail``), resolved by :func:`robot_callback`."""
    return typer.Option("--robot", callback=robot_callback, help=ROBOT_HELP + help_tail)


def robot_protocol(value: str, option: str = "--robot") -> str:
    """The ``[robot] protocol`` of the description ``value`` names: which fake
    robot ``demo`` and ``emulate`` start; a usage error (exit 2) if none."""
    try:
        return protocol_of(value)
    except OdohilError as exc:
        raise typer.BadParameter(str(exc), param_hint=option) from None
