"""``odohil predict``: expected observables of a forth-and-back design."""

from __future__ import annotations

import json
from typing import Annotated

import typer
from rich.console import Console

from odohil.cli.options import (
    K_OPTION,
    L_OPTION,
    UNITS_DEFAULT,
    JsonOption,
    Parameters,
    UnitsOption,
    VariantChoice,
    VariantOption,
    parameters_option,
    unit_system,
    usage_errors,
)
from odohil.cli.render import drawn
from odohil.science.closed_forms import forth_and_back_means
from odohil.science.paths import Design
from odohil.session.commands.design import predict_document
from odohil.session.commands.design_tables import predict_table


@parameters_option
def predict(
    k: Annotated[float, K_OPTION],
    l_m: Annotated[float, L_OPTION],
    variant: VariantOption = VariantChoice.turn,
    as_json: JsonOption = False,
    units_choice: UnitsOption = UNITS_DEFAULT,
    *,
    params: Parameters,
) -> None:
    """Predict phi1..phi5, <x>, <y> for k forth-and-back runs of length l.

    Parameters are in the paper's units and default to the Nomad 150 values.
    """
    with usage_errors():
        design = Design(k, l_m, variant.value)
    means = forth_and_back_means(design, params)
    if as_json:
        typer.echo(json.dumps(predict_document(design, params, means), indent=2))
        return
    Console().print(drawn(predict_table(design, params, means, unit_system(units_choice))))
