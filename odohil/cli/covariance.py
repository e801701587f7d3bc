"""``odohil covariance``: mean and covariance of the odometry pose change of a path."""

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
from odohil.science.covariance import SimulatedMoments, predicted_moments, simulated_moments
from odohil.science.limits import check_simulation_work, segments_of
from odohil.science.moments import PoseMoments
from odohil.science.parameters import ErrorParameters
from odohil.science.paths import Design, EncoderPath, square
from odohil.science.simulator import DEFAULT_SEGMENT_M

COMPONENTS = ("x", "y", "Delta")
COMPONENT_UNITS = ("m", "m", "rad")


class PathChoice(StrEnum):
    """The kind of path."""

    forth_and_back = "forth-and-back"
    square = "square"


def _path(
    kind: PathChoice | None,
    k: float | None,
    l_m: float | None,
    variant: VariantChoice,
    side: float | None,
) -> EncoderPath:
    if kind is None:  # the path the options name: --k/--l or --side
        if side is not None and k is None and l_m is None:
            kind = PathChoice.square
        elif side is None and (k is not None or l_m is not None):
            kind = PathChoice.forth_and_back
        else:
            raise typer.BadParameter(
                "give --k K --l L (forth-and-back) or --side S (square), not both"
                if side is not None
                else "give --k K --l L (forth-and-back) or --side S (square)"
            )
    if kind is PathChoice.forth_and_back:
        if k is None or l_m is None:
            raise typer.BadParameter("--path forth-and-back needs --k and --l")
        if side is not None:
            raise typer.BadParameter("--side is for --path square")
        return Design(k, l_m, variant.value).path()
    if side is None:
        raise typer.BadParameter("--path square needs --side")
    if k is not None or l_m is not None:
        raise typer.BadParameter("--k and --l are for --path forth-and-back")
    return square(side)


def _matrix_dict(matrix: object) -> list[list[float]]:
    return [[float(v) for v in row] for row in matrix]  # type: ignore[attr-defined]


def _document(
    path: EncoderPath,
    params: ErrorParameters,
    exact: PoseMoments,
    sim: SimulatedMoments | None,
) -> dict[str, object]:
    document: dict[str, object] = {
        "path": path.name,
        "distance_m": path.distance_m,
        "parameters_si": params.to_si_dict(),
        "components": list(COMPONENTS),
        "units": {"mean": list(COMPONENT_UNITS), "cov": "products of the component units"},
        "closed_form": {"mean": [float(v) for v in exact.mean], "cov": _matrix_dict(exact.cov)},
    }
    if sim is not None:
        document["simulated"] = {
            "n_trials": sim.n_trials,
            "mean": [float(v) for v in sim.mean],
            "mean_se": [float(v) for v in sim.mean_se],
            "cov": _matrix_dict(sim.cov),
            "cov_se": _matrix_dict(sim.cov_se),
        }
    return document


def _print(
    path: EncoderPath,
    exact: PoseMoments,
    sim: SimulatedMoments | None,
    params: ErrorParameters,
    system: units.UnitSystem,
) -> None:
    console = Console()
    table = Table(
        title=f"Pose change after {path.name} ({path.distance_m:g} m driven)",
        caption=parameters_line(params.to_si_dict(), system),
    )
    table.add_column("quantity")
    table.add_column("closed form", justify="right")
    if sim is not None:
        table.add_column(
            f"simulated ({units.plural(sim.n_trials, 'trial')}) +- MC se", justify="right"
        )
    for i, (name, unit) in enumerate(zip(COMPONENTS, COMPONENT_UNITS, strict=True)):
        row = [f"mean {name} ({unit})", f"{exact.mean[i]:.6g}"]
        if sim is not None:
            row.append(f"{sim.mean[i]:.6g} +- {sim.mean_se[i]:.2g}")
        table.add_row(*row)
    for i in range(3):
        for j in range(i, 3):
            unit = units.product_unit(COMPONENT_UNITS[i], COMPONENT_UNITS[j])
            row = [f"cov({COMPONENTS[i]}, {COMPONENTS[j]}) ({unit})", f"{exact.cov[i, j]:.6g}"]
            if sim is not None:
                row.append(f"{sim.cov[i, j]:.6g} +- {sim.cov_se[i, j]:.2g}")
            table.add_row(*row)
    sd = [math.sqrt(max(exact.cov[i, i], 0.0)) for i in range(3)]
    table.add_row(
        "sd x, y (mm); sd Delta (deg)",
        f"{sd[0] * 1e3:.4g}, {sd[1] * 1e3:.4g}; {math.degrees(sd[2]):.4g}",
        *([""] if sim is not None else []),
    )
    console.print(table)


def covariance(
    path_kind: Annotated[
        PathChoice | None,
        typer.Option(
            "--path",
            help="forth-and-back or square (default: the one --k/--l or --side names).",
        ),
    ] = None,
    k: float | None = typer.Option(
        None, "--k", callback=bounded("k"), help="Forth-and-back pairs, a multiple of 1/2."
    ),
    l_m: float | None = typer.Option(
        None, "--l", callback=bounded("l"), help="Forth-and-back leg length, m."
    ),
    variant: VariantOption = VariantChoice.turn,
    side: float | None = typer.Option(
        None, "--side", callback=bounded("side"), help="Square side, m."
    ),
    e_r: ERDegPerM = E_R_DEFAULT,
    e_t: ETOption = E_T_DEFAULT,
    k_theta: KThetaDeg2PerM = K_THETA_DEFAULT,
    k_rho: KRhoM = K_RHO_DEFAULT,
    n_simulate: int | None = typer.Option(
        None,
        "--simulate",
        callback=bounded("n_simulate"),
        help="Also simulate this many trials (discrete model).",
    ),
    seed: int | None = typer.Option(
        None, "--seed", callback=bounded("seed"), help="Seed of the simulation."
    ),
    segment_m: float = typer.Option(
        DEFAULT_SEGMENT_M,
        "--segment-m",
        callback=bounded("segment_m"),
        help="Segment length of the simulation, m.",
    ),
    as_json: bool = typer.Option(False, "--json", help="Print SI values as JSON."),
    units_choice: UnitsOption = UNITS_DEFAULT,
) -> None:
    """Mean and covariance of the pose change (x, y, Delta) after a path.

    Closed form, and simulated if asked. Parameters in the paper's units
    (default: Nomad 150).
    """
    if n_simulate is not None and n_simulate < 2:
        raise typer.BadParameter(f"--simulate needs at least 2 trials, got {n_simulate}")
    try:
        path = _path(path_kind, k, l_m, variant, side)
        params = parameters_from_paper_units(e_r, e_t, k_theta, k_rho)
        if n_simulate is not None:
            legs = path.legs.length_m.tolist()
            check_simulation_work(n_simulate, segments_of(legs, segment_m))
        exact = predicted_moments(path, params)
        sim = (
            simulated_moments(path, params, n_simulate, seed=seed, segment_m=segment_m)
            if n_simulate is not None
            else None
        )
    except OdohilError as exc:
        raise typer.BadParameter(str(exc)) from exc
    if as_json:
        typer.echo(json.dumps(_document(path, params, exact, sim), indent=2))
    else:
        _print(path, exact, sim, params, unit_system(units_choice))


def register(app: typer.Typer) -> None:
    """Add ``covariance`` to the ``odohil`` app."""
    app.command("covariance")(covariance)
