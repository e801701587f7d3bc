"""``odohil covariance``: mean and covariance of the odometry pose change of a
path (odohil/session/commands/design.py computes)."""

from __future__ import annotations

import json
from enum import StrEnum
from typing import Annotated

import typer
from rich.console import Console

from odohil.cli.options import (
    K_OPTION,
    L_OPTION,
    SEGMENT_OPTION,
    UNITS_DEFAULT,
    JsonOption,
    Parameters,
    UnitsOption,
    VariantChoice,
    VariantOption,
    option,
    parameters_option,
    unit_system,
    usage_errors,
)
from odohil.cli.render import drawn
from odohil.science.simulator import DEFAULT_SEGMENT_M
from odohil.session.commands.design import covariance_document, named_path, path_moments
from odohil.session.commands.design_tables import covariance_table


class PathChoice(StrEnum):
    """The kind of path."""

    forth_and_back = "forth-and-back"
    square = "square"


@parameters_option
def covariance(
    path_kind: Annotated[
        PathChoice | None,
        option("--path", help="forth-and-back or square (default: what --k/--l or --side name)."),
    ] = None,
    k: Annotated[float | None, K_OPTION] = None,
    l_m: Annotated[float | None, L_OPTION] = None,
    variant: VariantOption = VariantChoice.turn,
    side: Annotated[float | None, option("--side", bound="side", help="Square side, m.")] = None,
    n_simulate: Annotated[
        int | None,
        option("--simulate", bound="n_simulate", help="Also simulate this many trials."),
    ] = None,
    seed: Annotated[int | None, option("--seed", bound="seed", help="Simulation seed.")] = None,
    segment_m: Annotated[float, SEGMENT_OPTION] = DEFAULT_SEGMENT_M,
    as_json: JsonOption = False,
    units_choice: UnitsOption = UNITS_DEFAULT,
    *,
    params: Parameters,
) -> None:
    """Mean and covariance of the pose change (x, y, Delta) after a path.

    Closed form, and simulated if asked. Parameters in the paper's units
    (default: Nomad 150).
    """
    with usage_errors():
        kind = None if path_kind is None else path_kind.value
        path = named_path(kind, k, l_m, variant.value, side)
        exact, sim = path_moments(path, params, n_simulate, seed, segment_m)
    if as_json:
        typer.echo(json.dumps(covariance_document(path, params, exact, sim), indent=2))
        return
    shown = covariance_table(path, params, exact, sim, unit_system(units_choice))
    Console().print(drawn(shown))
