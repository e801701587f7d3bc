"""``odohil predict``: expected observables of a forth-and-back design."""

from __future__ import annotations

import json

import typer
from rich.console import Console
from rich.table import Table

from odohil import units
from odohil.cli.options import (
    E_R_DEFAULT,
    E_T_DEFAULT,
    K_RHO_DEFAULT,
    K_THETA_DEFAULT,
    UNITS_DEFAULT,
    ERDegPerM,
    ETOption,
    KRhoM,
    KThetaDeg2PerM,
    UnitsOption,
    VariantChoice,
    VariantOption,
    bounded,
    parameters_from_paper_units,
    unit_system,
)
from odohil.cli.render import parameters_line
from odohil.errors import OdohilError
from odohil.science.closed_forms import ObservableMeans, forth_and_back_means
from odohil.science.parameters import SI_UNITS, ErrorParameters
from odohil.science.paths import Design

SI_OBSERVABLE_UNITS = {
    "phi1": "rad",
    "phi2": "rad^2",
    "phi3": "m",
    "phi4": "m",
    "phi5": "m^2",
    "x": "m",
    "y": "m",
}

_MEANING = {
    "phi1": "mean heading change",
    "phi2": "variance of the heading change",
    "phi3": "mean x of the end point",
    "phi4": "mean y of the end point",
    "phi5": "mean squared distance start-end",
    "x": "<x>",
    "y": "<y>",
}


def _degrees(key: str, value: float) -> str:
    if key == "phi1":
        return f"{units.radians_to_degrees(value):.6g} deg"
    if key == "phi2":
        return f"{units.rad2_to_deg2(value):.6g} deg^2"
    return ""


def _table(
    design: Design, params: ErrorParameters, means: ObservableMeans, system: units.UnitSystem
) -> Table:
    table = Table(
        title=f"Expected observables, forth and back {design.label()} "
        f"(rho = {design.distance_m:g} m)",
        caption=parameters_line(params.to_si_dict(), system) + f" (1+E_T = {1.0 + params.e_t:g})",
    )
    table.add_column("observable")
    table.add_column("meaning")
    table.add_column("value (SI)", justify="right")
    table.add_column("unit")
    table.add_column("in degrees", justify="right")
    for key, value in means.as_dict().items():
        unit = SI_OBSERVABLE_UNITS[key]
        table.add_row(key, _MEANING[key], f"{value:.6g}", unit, _degrees(key, value))
    return table


def _json(design: Design, params: ErrorParameters, means: ObservableMeans) -> str:
    document: dict[str, object] = dict(means.as_dict())
    document["design"] = {"k": design.k, "l_m": design.l_m, "variant": design.variant}
    document["parameters"] = params.to_si_dict()
    document["units"] = {
        **SI_OBSERVABLE_UNITS,
        "parameters": dict(SI_UNITS),
        "design": {"k": "1", "l_m": "m"},
    }
    return json.dumps(document, indent=2)


def predict(
    k: float = typer.Option(
        ..., "--k", callback=bounded("k"), help="Forth-and-back pairs k, a multiple of 1/2."
    ),
    l_m: float = typer.Option(..., "--l", callback=bounded("l"), help="Leg length l, metres."),
    variant: VariantOption = VariantChoice.turn,
    e_r: ERDegPerM = E_R_DEFAULT,
    e_t: ETOption = E_T_DEFAULT,
    k_theta: KThetaDeg2PerM = K_THETA_DEFAULT,
    k_rho: KRhoM = K_RHO_DEFAULT,
    as_json: bool = typer.Option(False, "--json", help="Print SI values as JSON."),
    units_choice: UnitsOption = UNITS_DEFAULT,
) -> None:
    """Predict phi1..phi5, <x>, <y> for k forth-and-back runs of length l.

    Parameters are in the paper's units and default to the Nomad 150 values.
    """
    for option, value in (("--K-theta", k_theta), ("--K-rho", k_rho)):
        if value < 0:
            raise typer.BadParameter(f"{option} is a variance rate and cannot be negative: {value}")
    try:
        design = Design(k, l_m, variant.value)
    except OdohilError as exc:
        raise typer.BadParameter(str(exc)) from exc
    params = parameters_from_paper_units(e_r, e_t, k_theta, k_rho)
    means = forth_and_back_means(design, params)
    if as_json:
        typer.echo(_json(design, params, means))
    else:
        Console().print(_table(design, params, means, unit_system(units_choice)))


def register(app: typer.Typer) -> None:
    """Add ``predict`` to the ``odohil`` app."""
    app.command("predict")(predict)
