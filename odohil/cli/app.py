"""The ``odohil`` command: one typer app; each command lives in its own module.

A command module defines ``register(app: typer.Typer) -> None``; add its name
to ``COMMAND_MODULES`` to expose it.
"""

from __future__ import annotations

import importlib

import typer

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

app = typer.Typer(
    name="odohil",
    help="Calibrate the odometry error of a synchronous-drive mobile robot "
    "(Martinelli's E_R, E_T, K_theta, K_rho) with the robot in the loop.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)


def _version(value: bool) -> None:
    if value:
        typer.echo(f"odohil {__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    version: bool = typer.Option(
        False, "--version", callback=_version, is_eager=True, help="Show the version and exit."
    ),
) -> None:
    """Calibrate odometry: predict, simulate, talk to the robot, estimate."""


for _name in COMMAND_MODULES:
    importlib.import_module(f"odohil.cli.{_name}").register(app)


def main() -> None:
    """Entry point of the ``odohil`` console script."""
    app()
