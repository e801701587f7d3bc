"""Command-line options shared by several commands, declared once: the four
error parameters in the paper's units (defaults: the paper's Nomad 150 values),
the forth-and-back variant, units, ``--robot`` (a robot description file, or
the name of a built-in one: odohil/session/robots/description.py finds it; anything
else is a usage error, exit 2, naming the option and the names), and the
options of the commands that run a session (port, baud, truth socket, --json,
--exclude, --allow-turns)."""

from __future__ import annotations

import contextlib
import functools
import inspect
from collections.abc import Callable, Iterable, Iterator, Sequence
from enum import StrEnum
from pathlib import Path
from typing import Annotated, Any, TypeVar, cast

import typer

from odohil import units
from odohil.errors import OdohilError
from odohil.science.limits import RANGES
from odohil.science.parameters import NOMAD150, ErrorParameters
from odohil.session.robots.description import builtin_names, resolve_robot

N = TypeVar("N", int, float, int | None, float | None)
Command = Callable[..., None]


def add_options(
    added: Sequence[inspect.Parameter],
    typed: Sequence[str],
    resolve: Callable[[dict[str, Any]], dict[str, Any]],
) -> Callable[[Command], Command]:
    """A decorator that gives a command the options ``added``: ``resolve``
    takes their values out of the command's arguments and gives the typed
    values of the command's parameters ``typed`` (which the command line
    then does not show). Options declared and resolved once for many commands."""

    def decorate(command: Command) -> Command:
        signature = inspect.signature(command, eval_str=True)
        kept = [p for p in signature.parameters.values() if p.name not in typed]

        @functools.wraps(command)
        def wrapper(**values: Any) -> None:
            typed = resolve(values)  # takes the raw values out
            command(**values, **typed)

        del wrapper.__wrapped__
        parameters = kept + list(added)
        wrapper.__signature__ = signature.replace(parameters=parameters)  # type: ignore[attr-defined]
        wrapper.__annotations__ = {p.name: p.annotation for p in parameters}
        return wrapper

    return decorate


@contextlib.contextmanager
def usage_errors(param_hint: str | None = None) -> Iterator[None]:
    """Within: an odohil error is a usage error (exit 2), naming ``param_hint``."""
    try:
        yield
    except OdohilError as exc:
        raise typer.BadParameter(str(exc), param_hint=param_hint) from exc


def keyword(name: str, kind: Any, default: Any, *flags: str, help: str) -> inspect.Parameter:
    """An option as a keyword parameter of a command (for :func:`add_options`);
    a flag with a range in ``RANGES`` (``--E-R`` ...) is checked against it."""
    bound = flags[0][2:].replace("-", "_")
    made = option(*flags, help=help, bound=bound if bound in RANGES else None)
    return inspect.Parameter(
        name, inspect.Parameter.KEYWORD_ONLY, default=default, annotation=Annotated[kind, made]
    )


def bounded(name: str) -> Callable[[N], N]:
    """A typer callback that refuses a value outside ``RANGES[name]`` (or not
    finite) with a usage error (exit 2) naming the option and the range.
    None (an option not given) passes."""

    def callback(ctx: typer.Context, param: typer.CallbackParam, value: N) -> N:
        if value is None:
            return value
        option = param.opts[0] if param.opts else name
        try:
            RANGES[name].check(option, value)
        except OdohilError as exc:
            raise typer.BadParameter(str(exc)) from None
        return value

    return callback  # type: ignore[return-value]


def option(*flags: str, help: str, bound: str | None = None) -> Any:
    """``typer.Option(*flags, help=help)``, its value checked against
    ``RANGES[bound]`` when ``bound`` is given (:func:`bounded`)."""
    return typer.Option(*flags, help=help, callback=None if bound is None else bounded(bound))


K_OPTION = option("--k", bound="k", help="Forth-and-back pairs k, a multiple of 1/2.")
L_OPTION = option("--l", bound="l", help="Leg length l of the forth-and-back runs, m.")
SEGMENT_OPTION = option("--segment-m", bound="segment_m", help="Largest simulated segment, m.")
JsonOption = Annotated[bool, typer.Option("--json", help="Print the result as JSON (SI); when "
    'refused (exit 2), {"status": "refused", "exit_code": 2, "error": ...}.')]  # fmt: skip


PAPER_DEFAULTS = NOMAD150.to_paper_units()
"""The Nomad 150 values in the paper's units (deg/m, 1, deg^2/m, m)."""
_E_T_HELP = "Systematic E_T (no unit; the paper's 1+E_T = 0.98 is -0.02)."
_PARAMETER_OPTIONS = (  # (parameter, flag, help)
    ("e_r", "--E-R", "Systematic E_R, deg/m."), ("e_t", "--E-T", _E_T_HELP),
    ("k_theta", "--K-theta", "K_theta, deg^2/m."), ("k_rho", "--K-rho", "K_rho, m."),
)  # fmt: skip


def choices(name: str, values: Iterable[str]) -> type[StrEnum]:
    """A :class:`~enum.StrEnum` of ``values`` (names and values) for typer's choices, from a
    registry (log readers, export formats): a new format is its module and its entry."""
    functional: Callable[..., object] = StrEnum  # mypy reads only literal names here
    return cast("type[StrEnum]", functional(name, [(value, value) for value in values]))


class VariantChoice(StrEnum):
    """How the robot comes back: turn in place, or drive backwards."""

    turn = "turn"
    reverse = "reverse"


VariantOption = Annotated[
    VariantChoice,
    typer.Option("--variant", help="turn: 180 deg in place; reverse: drive back."),
]


def _parameters(values: dict[str, Any]) -> dict[str, Any]:
    given = [values.pop(name) for name, _, _ in _PARAMETER_OPTIONS]
    try:
        return {"params": ErrorParameters.from_paper_units(*given)}
    except OdohilError as exc:
        raise typer.BadParameter(str(exc)) from exc


Parameters = ErrorParameters
parameters_option = add_options(
    [
        keyword(name, float, PAPER_DEFAULTS[flag[2:].replace("-", "_")], flag, help=text)
        for name, flag, text in _PARAMETER_OPTIONS
    ],
    ["params"],
    _parameters,
)
"""Gives a command ``--E-R``, ``--E-T``, ``--K-theta``, ``--K-rho`` (the paper's
units; default: the Nomad 150) as its keyword parameter ``params``
(:class:`~odohil.science.parameters.ErrorParameters`); bad values exit 2."""


class UnitsChoice(StrEnum):
    """How parameters are printed for people (JSON is always SI)."""

    paper = "paper"
    si = "si"


UnitsOption = Annotated[UnitsChoice, typer.Option("--units", help="Parameters printed in the "
    "paper's units (E_R deg/m, K_theta deg^2/m) or SI (rad/m, rad^2/m); E_T is a plain number, "
    "K_rho metres. JSON is always SI.")]  # fmt: skip
UNITS_DEFAULT = UnitsChoice(units.DEFAULT_UNIT_SYSTEM)
"""The same default on every command."""


def unit_system(choice: UnitsChoice) -> units.UnitSystem:
    """The choice as :mod:`odohil.units` names it."""
    return "si" if choice is UnitsChoice.si else "paper"


EXCLUDE_HELP = ("Trial numbers to leave out of the estimate, comma-separated (e.g. 3,17); "
                "the journal and files keep every trial.")  # fmt: skip
ExcludeOption = Annotated[str | None, typer.Option("--exclude", help=EXCLUDE_HELP)]
PortOption = Annotated[str | None, typer.Option("--port", help="Serial device, pty path or "
    "pyserial URL (default: the session's, else robot.toml \\[serial] port).")]  # fmt: skip
BaudOption = Annotated[int | None, option("--baud", bound="baud", help="Line speed (default: "
    "the session's, else robot.toml \\[serial] baud, else the robot's default).")]  # fmt: skip
TruthSocketOption = Annotated[str | None, typer.Option("--truth-socket",
    help="The fake robot's truth socket (for --measure fake).")]  # fmt: skip
RunJsonOption = Annotated[bool, typer.Option("--json", help="Print one JSON object (SI): the "
    'final estimate (as estimate --json) with "status": "finished"; when interrupted or failed, '
    'the status, the signal, whether the stop was confirmed and the partial estimate; when '
    'refused, "status": "refused", the exit code and the error.')]  # fmt: skip
ALLOW_TURNS_HELP = ("Run `turn` designs on a robot whose turns carry error (\\[robot] "
                    "turns_exact = false); the estimate is then not trusted.")  # fmt: skip
AllowTurnsOption = Annotated[bool, typer.Option("--allow-turns", help=ALLOW_TURNS_HELP)]
ROBOT_HELP = f"Robot description (TOML file), or a built-in one: {', '.join(builtin_names())}."


def robot_callback(
    ctx: typer.Context, param: typer.CallbackParam, value: Path | None
) -> Path | None:
    """A typer callback for ``--robot``: the resolved file, or None when not given."""
    if value is None:
        return None
    with usage_errors(param.opts[0]):
        return resolve_robot(value)


def robot_option(help_tail: str = "") -> Any:
    """``--robot`` (:data:`ROBOT_HELP` and ``help_tail``), resolved by :func:`robot_callback`."""
    return typer.Option("--robot", callback=robot_callback, help=ROBOT_HELP + help_tail)
