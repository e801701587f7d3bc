"""``odohil plan``: recommend calibration designs for a budget."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console
from rich.table import Table

from odohil import units
from odohil.cli.options import E_R_DEFAULT, E_T_DEFAULT, K_RHO_DEFAULT, K_THETA_DEFAULT, bounded
from odohil.errors import OdohilError
from odohil.science.fisher import default_description
from odohil.science.parameters import (
    PAPER_UNITS,
    PARAMETER_NAMES,
    SI_UNITS,
    ErrorParameters,
)
from odohil.science.planner import (
    DEFAULT_FLOOR_M,
    DEFAULT_MAX_LEG_M,
    MAX_DESIGNS,
    Plan,
    plan_experiment,
)
from odohil.science.robot_description import MAX_FLOOR_M, RobotDescription
from odohil.session.robot_file import load_robot_description

DEFAULT_SIGMA_M = 0.001


def _measurement(sigma_m: float | None, robot: Path | None) -> tuple[RobotDescription, str]:
    if sigma_m is not None and robot is not None:
        raise typer.BadParameter("give either --sigma-m or --robot, not both")
    try:
        if robot is not None:
            return load_robot_description(robot), f"robot description {robot}"
        sigma = DEFAULT_SIGMA_M if sigma_m is None else sigma_m
        if not math.isfinite(sigma) or sigma <= 0:
            raise typer.BadParameter(f"--sigma-m must be a positive number of metres, got {sigma}")
        return default_description(sigma), (
            f"tape sigma {sigma:g} m, screws on a 0.2 m radius circle, one cross distance"
        )
    except OdohilError as exc:
        raise typer.BadParameter(str(exc)) from exc


def _document(plan: Plan, prior: ErrorParameters, measurement: str) -> dict[str, object]:
    errors = {}
    for name, se in zip(PARAMETER_NAMES, plan.standard_errors, strict=True):
        entry: dict[str, object] = {
            "stderr_si": float(se),
            "unit_si": SI_UNITS[name],
            "stderr_paper": units.parameter_to_paper(name, float(se)),
            "unit_paper": PAPER_UNITS[name],
        }
        if name in plan.targets:
            entry["target_si"] = plan.targets[name]
            entry["ratio_to_target"] = float(se) / plan.targets[name]
        errors[name] = entry
    return {
        "designs": [
            {
                "k": item.design.k,
                "l_m": item.design.l_m,
                "variant": item.design.variant,
                "n_trials": item.n_trials,
                "distance_m": item.distance_m,
            }
            for item in plan.items
        ],
        "distance_m": plan.distance_m,
        "floor_needed_m": plan.excursion_m,
        "n_trials": plan.n_trials,
        "expected_stderr": errors,
        "criterion": plan.criterion,
        "meets_targets": plan.meets_targets if plan.targets else None,
        "prior_si": prior.to_si_dict(),
        "measurement": measurement,
    }


def _print(plan: Plan, prior: ErrorParameters, measurement: str, budget_m: float) -> None:
    console = Console()
    designs = Table(
        title=f"Recommended plan: {plan.distance_m:g} m of {budget_m:g} m, {plan.n_trials} trials"
    )
    for column in ("k", "l (m)", "variant", "trials", "metres"):
        designs.add_column(column, justify="right")
    for item in plan.items:
        designs.add_row(
            f"{item.design.k:g}",
            f"{item.design.l_m:g}",
            item.design.variant,
            str(item.n_trials),
            f"{item.distance_m:g}",
        )
    console.print(designs)
    console.print(
        f"free floor needed: {plan.excursion_m:g} m (one-way trials alternate and come back)"
    )
    errors = Table(title="Expected standard errors (Cramer-Rao)", caption=measurement)
    for column in ("parameter", "prior (paper)", "stderr (paper)", "stderr (SI)", "target"):
        errors.add_column(column, justify="right")
    paper_prior = prior.to_paper_units()
    for name, se in zip(PARAMETER_NAMES, plan.standard_errors, strict=True):
        target = ""
        if name in plan.targets:
            ratio = float(se) / plan.targets[name]
            target = f"{units.parameter_to_paper(name, plan.targets[name]):.3g} ({ratio:.2f}x)"
        errors.add_row(
            name,
            f"{paper_prior[name]:.4g} {PAPER_UNITS[name]}",
            f"{units.parameter_to_paper(name, float(se)):.3g} {PAPER_UNITS[name]}",
            f"{float(se):.3g} {SI_UNITS[name]}",
            target,
        )
    console.print(errors)
    if plan.targets:
        verdict = "meets every target" if plan.meets_targets else "does NOT meet every target"
        console.print(f"The plan {verdict} (largest stderr/target = {plan.criterion:.3f}).")


def plan(
    budget_m: float = typer.Option(
        ..., "--budget-m", callback=bounded("budget_m"), help="Most metres driven in all."
    ),
    max_trials: int | None = typer.Option(
        None,
        "--max-trials",
        callback=bounded("max_trials"),
        help="Most trials in all (each is marked and measured).",
    ),
    e_r: float = typer.Option(
        E_R_DEFAULT, "--E-R", callback=bounded("E_R"), help="Prior guess of E_R, deg/m."
    ),
    e_t: float = typer.Option(
        E_T_DEFAULT, "--E-T", callback=bounded("E_T"), help="Prior guess of E_T (no unit)."
    ),
    k_theta: float = typer.Option(
        K_THETA_DEFAULT, "--K-theta", callback=bounded("K_theta"), help="Prior K_theta, deg^2/m."
    ),
    k_rho: float = typer.Option(
        K_RHO_DEFAULT, "--K-rho", callback=bounded("K_rho"), help="Prior K_rho, m."
    ),
    sigma_m: float | None = typer.Option(
        None,
        "--sigma-m",
        callback=bounded("sigma_m"),
        help=f"Tape sigma of one floor-mark distance, m (default {DEFAULT_SIGMA_M}), with "
        "three screws on a 0.2 m radius circle and one cross distance.",
    ),
    robot: Annotated[
        Path | None,
        typer.Option("--robot", help="Robot description (TOML): screws, sigma_m, cross pairs."),
    ] = None,
    target_e_r: float | None = typer.Option(
        None, "--target-E-R", callback=bounded("target_E_R"), help="Wanted stderr, deg/m."
    ),
    target_e_t: float | None = typer.Option(
        None, "--target-E-T", callback=bounded("target_E_T"), help="Wanted stderr of E_T."
    ),
    target_k_theta: float | None = typer.Option(
        None, "--target-K-theta", callback=bounded("target_K_theta"), help="Wanted stderr, deg^2/m."
    ),
    target_k_rho: float | None = typer.Option(
        None, "--target-K-rho", callback=bounded("target_K_rho"), help="Wanted stderr, m."
    ),
    max_designs: int = typer.Option(
        2,
        "--max-designs",
        callback=bounded("max_designs"),
        help=f"Mix at most this many designs (1 to {MAX_DESIGNS}).",
    ),
    max_leg_m: float = typer.Option(
        DEFAULT_MAX_LEG_M,
        "--max-leg-m",
        callback=bounded("max_leg_m"),
        help="Longest leg the floor allows, m.",
    ),
    floor_m: float | None = typer.Option(
        None,
        "--floor-m",
        help=f"Free floor along the line of travel, m, (0, {MAX_FLOOR_M:g}] (default: the "
        f"robot description's [floor] length_m, else {DEFAULT_FLOOR_M:g}).",
    ),
    as_json: bool = typer.Option(False, "--json", help="Print the plan as JSON."),
) -> None:
    """Recommend designs for a budget; print each parameter's expected stderr.

    Priors are in the paper's units (default: the Nomad 150 values). With
    targets, the plan minimises the largest stderr/target ratio; without, the
    sum of squared relative standard errors.
    """
    description, measurement = _measurement(sigma_m, robot)
    targets_paper = {
        "E_R": target_e_r,
        "E_T": target_e_t,
        "K_theta": target_k_theta,
        "K_rho": target_k_rho,
    }
    for name, value in targets_paper.items():
        if value is not None and (not math.isfinite(value) or value <= 0):
            raise typer.BadParameter(f"--target-{name.replace('_', '-')} must be positive")
    targets = {
        n: units.parameter_from_paper(n, v) for n, v in targets_paper.items() if v is not None
    }
    try:
        prior = ErrorParameters.from_paper_units(e_r, e_t, k_theta, k_rho)
        if not math.isfinite(max_leg_m) or max_leg_m <= 0:
            raise typer.BadParameter(f"--max-leg-m must be a positive length, got {max_leg_m}")
        if floor_m is not None and (not math.isfinite(floor_m) or not 0 < floor_m <= MAX_FLOOR_M):
            raise typer.BadParameter(
                f"--floor-m must be a length in (0, {MAX_FLOOR_M:g}] m, got {floor_m}"
            )
        floor = floor_m if floor_m is not None else description.floor_length_m
        result = plan_experiment(
            prior,
            budget_m,
            max_trials=max_trials,
            description=description,
            targets=targets,
            max_designs=max_designs,
            max_leg_m=max_leg_m,
            floor_m=floor,
        )
    except OdohilError as exc:
        raise typer.BadParameter(str(exc)) from exc
    if as_json:
        typer.echo(json.dumps(_document(result, prior, measurement), indent=2))
    else:
        _print(result, prior, measurement, budget_m)


def register(app: typer.Typer) -> None:
    """Add ``plan`` to the ``odohil`` app."""
    app.command("plan")(plan)
