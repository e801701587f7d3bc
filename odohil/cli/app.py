"""The ``odohil`` command: one typer app; each command lives in its own module.

A command module defines the command as a function of the module's name (the
command's name, but for :data:`_COMMAND_NAMES`), or a ``register(app)`` that
adds it otherwise (validate's help text); add the module's name to
``COMMAND_MODULES`` to expose it. The console script running one command
imports that command's module only (``odohil emulate`` loads no estimator and
no scipy.stats); an import from elsewhere (tests, ``--help``) registers all.
"""

from __future__ import annotations

import importlib
import json
import sys
from pathlib import Path
from typing import Any

import typer
from typer._click.exceptions import ClickException
from typer.core import TyperGroup

from odohil import __version__

COMMAND_MODULES: tuple[str, ...] = (
    "emulate",
    "predict",
    "simulate",
    "plan",
    "covariance",
    "run",
    "resume",
    "demo",
    "report",
    "export",
    "estimate",
    "wizard",
    "validate",
    "import_log",
)


def _no_flag_metavars(command: Any, ctx: Any) -> None:
    """A flag takes no value: show no type beside it (typer shows ``<bool>``);
    ``--help`` included."""
    if command is None:
        return
    for param in command.get_params(ctx):
        if getattr(param, "is_flag", False):
            param.metavar = ""


class OdohilGroup(TyperGroup):
    """The ``odohil`` group: its commands' help shows no metavar on flags."""

    def get_command(self, ctx: Any, cmd_name: str) -> Any:
        """The command ``cmd_name``, its flags without metavar."""
        command = super().get_command(ctx, cmd_name)
        _no_flag_metavars(command, ctx)
        return command

    def invoke(self, ctx: Any) -> Any:
        """The command; with ``--json`` a refusal (bad option, bad input, failed pre-flight)
        is also one JSON object on stdout (odohil/session/run/running.py refused_before_run)."""
        as_json = "--json" in ctx.args
        try:
            return super().invoke(ctx)
        except (ClickException, typer.Exit) as exc:  # typer.Exit: bad_input's, refuse's note
            notes = getattr(exc, "__notes__", [""])
            said = exc.format_message() if isinstance(exc, ClickException) else notes[0]
            if as_json and said:
                from odohil.session.run.running import refused_before_run

                typer.echo(json.dumps(refused_before_run(said, exc.exit_code)))
            raise

    def format_help(self, ctx: Any, formatter: Any) -> None:
        """The group's help, its own flags without metavar."""
        _no_flag_metavars(self, ctx)
        super().format_help(ctx, formatter)


app = typer.Typer(
    name="odohil",
    cls=OdohilGroup,
    help="Calibrate the odometry error of a mobile robot (Martinelli's E_R, E_T, "
    "K_theta, K_rho) with the robot in the loop: a synchronous drive (the Nomad 150) "
    "or a differential drive (the iRobot Create 2), or another through a robot backend.",
    no_args_is_help=True,
    add_completion=True,
    pretty_exceptions_enable=False,
)


_VERSION_FLAGS = ("--version", "-V")
"""The root's eager flags that print and exit before any command is looked at."""


def _version(value: bool) -> None:
    if value:
        typer.echo(f"odohil {__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    version: bool = typer.Option(
        False,
        *_VERSION_FLAGS,
        callback=_version,
        is_eager=True,
        help="Show the version and exit.",
    ),
) -> None:
    """Calibrate odometry: predict, simulate, talk to the robot, estimate."""


_COMMAND_NAMES = {"import": "import_log"}
"""Command names that differ from their module's name."""
_MODULE_COMMANDS = {module: command for command, module in _COMMAND_NAMES.items()}


def _modules_to_register(argv: list[str]) -> tuple[str, ...]:
    """The command modules to import: the named command's alone when this
    process is the console script (or ``python -m odohil``) and its first
    argument names a command, none when it asks for the version, else every
    one (a typo, ``--help``, an import)."""
    if len(argv) > 1 and Path(argv[0]).name in ("odohil", "__main__.py"):
        if argv[1] in _VERSION_FLAGS:
            return ()
        module = _COMMAND_NAMES.get(argv[1], argv[1])
        if module in COMMAND_MODULES:
            return (module,)
    return COMMAND_MODULES


for _name in _modules_to_register(sys.argv):
    _module = importlib.import_module(f"odohil.cli.{_name}")
    if hasattr(_module, "register"):
        _module.register(app)
    else:
        app.command(_MODULE_COMMANDS.get(_name, _name))(getattr(_module, _name))


def main() -> None:
    """Entry point of the ``odohil`` console script."""
    app()
