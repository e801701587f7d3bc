"""``odohil covariance``: mean and covariance of the odometry pose change of a
path (odohil/session/design_tools.py computes)."""

from __future__ import annotations

import json
import math
from enum import StrEnum
from typing import Annotated

import typer
from rich.console import Console
from rich.table import Table

from odohil import units
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
)
from odohil.errors import OdohilError
from odohil.science.simulator import DEFAULT_SEGMENT_M
from odohil.session.design_tools import (
    COMPONENT_UNITS,
    COMPONENTS,
    covariance_document,
    named_path,
    path_moments,
)
from odohil.session.outcome_text import parameters_line


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
    try:
        kind = None if path_kind is None else path_kind.value
        path = named_path(kind, k, l_m, variant.value, side)
        exact, sim = path_moments(path, params, n_simulate, seed, segment_m)
    except OdohilError as exc:
        raise typer.BadParameter(str(exc)) from exc
    if as_json:
        typer.echo(json.dumps(covariance_document(path, params, exact, sim), indent=2))
        return
    table = Table(
        title=f"Pose change after {path.name} ({path.distance_m:g} m driven)",
        caption=parameters_line(params.to_si_dict(), unit_system(units_choice)),
    )
    table.add_column("quantity")
    table.add_column("closed form", justify="right")
    if sim is not None:
        trials = units.plural(sim.n_trials, "trial")
        table.add_column(f"simulated ({trials}) +- MC se", justify="right")
    for i, (name, unit) in enumerate(zip(COMPONENTS, COMPONENT_UNITS, strict=True)):
        simulated = [] if sim is None else [f"{sim.mean[i]:.6g} +- {sim.mean_se[i]:.2g}"]
        table.add_row(f"mean {name} ({unit})", f"{exact.mean[i]:.6g}", *simulated)
    for i in range(3):
        for j in range(i, 3):
            unit = units.product_unit(COMPONENT_UNITS[i], COMPONENT_UNITS[j])
            simulated = [] if sim is None else [f"{sim.cov[i, j]:.6g} +- {sim.cov_se[i, j]:.2g}"]
            table.add_row(
                f"cov({COMPONENTS[i]}, {COMPONENTS[j]}) ({unit})",
                f"{exact.cov[i, j]:.6g}",
                *simulated,
            )
    sd = [math.sqrt(max(exact.cov[i, i], 0.0)) for i in range(3)]
    sds = f"{sd[0] * 1e3:.4g}, {sd[1] * 1e3:.4g}; {math.degrees(sd[2]):.4g}"
    table.add_row("sd x, y (mm); sd Delta (deg)", sds, *([""] if sim is not None else []))
    Console().print(table)
