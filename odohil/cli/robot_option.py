"""``--robot``: a robot description file, or the name of a built-in one.

The built-in descriptions are the TOML files shipped in the ``odohil.robots``
package (one per robot backend: ``nomad150``, ``create2``). A file of that name wins over a built-in
one; anything else is a usage error (exit 2) naming the option and the names.
"""

from __future__ import annotations

from importlib.resources import files
from pathlib import Path

import typer

from odohil.errors import OdohilError
from odohil.session.robot_file import load_robot_description

BUILTIN_PACKAGE = "odohil.robots"


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


ROBOT_HELP = f"Robot description (TOML file), or a built-in one: {', '.join(builtin_names())}."


def builtin_path(name: str) -> Path:
    """The file of the built-in description ``name`` (one of :func:`builtin_names`)."""
    return Path(str(files(BUILTIN_PACKAGE).joinpath(f"{name}.toml")))


def resolve_robot(value: str | Path, option: str = "--robot") -> Path:
    """The description file ``value`` names: itself when it is a file, else the
    built-in description of that name.

    Raises:
        typer.BadParameter: neither (the message names the option, the value
            and the built-in names).
    """
    path = Path(value)
    if path.is_file():
        return path
    names = builtin_names()
    if str(value) in names:
        return builtin_path(str(value))
    raise typer.BadParameter(
        f"cannot read {str(value)!r}: no such robot description file, and not the name "
        f"of a built-in description ({', '.join(names)})",
        param_hint=option,
    )


def robot_callback(
    ctx: typer.Context, param: typer.CallbackParam, value: Path | None
) -> Path | None:
    """A typer callback for ``--robot``: the resolved file, or None when not given."""
    if value is None:
        return None
    option = param.opts[0] if param.opts else "--robot"
    return resolve_robot(value, option)


def robot_protocol(value: str, option: str = "--robot") -> str:
    """The ``[robot] protocol`` of the description ``value`` names (a file or
    a built-in name): which fake robot ``demo`` and ``emulate`` start.

    Raises:
        typer.BadParameter: no such file or built-in name, or a file that is
            not a valid robot description.
    """
    path = resolve_robot(value, option)
    try:
        return load_robot_description(path).robot.protocol
    except OdohilError as exc:
        raise typer.BadParameter(str(exc), param_hint=option) from None
