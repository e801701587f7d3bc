"""Command-line options shared by several commands: the four error parameters
in the paper's units (defaults: the paper's Nomad 150 values) and the
forth-and-back variant."""

from __future__ import annotations

from collections.abc import Callable
from enum import StrEnum
from typing import Annotated, TypeVar

import typer

from odohil import units
from odohil.errors import OdohilError
from odohil.science.limits import RANGES
from odohil.science.parameters import NOMAD150, ErrorParameters

N = TypeVar("N", int, float, int | None, float | None)


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


PAPER_DEFAULTS = NOMAD150.to_paper_units()
"""The Nomad 150 values in the paper's units (deg/m, 1, deg^2/m, m)."""

E_R_DEFAULT = PAPER_DEFAULTS["E_R"]
E_T_DEFAULT = PAPER_DEFAULTS["E_T"]
K_THETA_DEFAULT = PAPER_DEFAULTS["K_theta"]
K_RHO_DEFAULT = PAPER_DEFAULTS["K_rho"]

ERDegPerM = Annotated[
    float, typer.Option("--E-R", help="Systematic E_R, deg/m.", callback=bounded("E_R"))
]
ETOption = Annotated[
    float,
    typer.Option(
        "--E-T",
        help="Systematic E_T (no unit; the paper's 1+E_T = 0.98 is -0.02).",
        callback=bounded("E_T"),
    ),
]
KThetaDeg2PerM = Annotated[
    float, typer.Option("--K-theta", help="K_theta, deg^2/m.", callback=bounded("K_theta"))
]
KRhoM = Annotated[float, typer.Option("--K-rho", help="K_rho, m.", callback=bounded("K_rho"))]


class VariantChoice(StrEnum):
    """How the robot comes back: turn in place, or drive backwards."""

    turn = "turn"
    reverse = "reverse"


VariantOption = Annotated[
    VariantChoice,
    typer.Option("--variant", help="turn: 180 deg in place; reverse: drive back."),
]


def parameters_from_paper_units(
    e_r: float, e_t: float, k_theta: float, k_rho: float
) -> ErrorParameters:
    """The parameters given on the command line, or a usage error (exit 2)
    that says what is wrong with them."""
    try:
        return ErrorParameters.from_paper_units(e_r, e_t, k_theta, k_rho)
    except OdohilError as exc:
        raise typer.BadParameter(str(exc)) from exc


class UnitsChoice(StrEnum):
    """How parameters are printed for people (JSON is always SI)."""

    paper = "paper"
    si = "si"


UnitsOption = Annotated[
    UnitsChoice,
    typer.Option(
        "--units",
        help="Parameters printed in the paper's units (E_R deg/m, K_theta deg^2/m) "
        "or SI (rad/m, rad^2/m); E_T is a plain number, K_rho metres. JSON is always SI.",
    ),
]
UNITS_DEFAULT = UnitsChoice(units.DEFAULT_UNIT_SYSTEM)
"""The same default on every command."""


def unit_system(choice: UnitsChoice) -> units.UnitSystem:
    """The choice as :mod:`odohil.units` names it."""
    return "si" if choice is UnitsChoice.si else "paper"
