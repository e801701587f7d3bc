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
from odohil.cli.options import (
    E_R_DEFAULT,
    E_T_DEFAULT,
    K_RHO_DEFAULT,
    K_THETA_DEFAULT,
    UNITS_DEFAULT,
    UnitsOption,
    bounded,
    unit_system,
)
from odohil.cli.robot_option import ROBOT_HELP, robot_callback
from odohil.cli.run import warn_turns
from odohil.errors import OdohilError
from odohil.science.fisher import default_description
from odohil.science.limits import RANGES
from odohil.science.parameters import (
    PAPER_UNITS,
    PARAMETER_NAMES,
    SI_UNITS,
    ErrorParameters,
)
from odohil.science.planner import (
    DEFAULT_FLOOR_M,
    DEFAULT_MAX_LEG_M,
    DEFAULT_MIN_TRIALS_PER_DESIGN,
    DEFAULT_SECONDS_PER_TRIAL,
    DEFAULT_SPEED_M_PER_S,
    DEFAULT_TURN_RATE_RAD_PER_S,
    MAX_DESIGNS,
    OperatorTime,
    Plan,
    evaluate_plan,
    plan_experiment,
)
from odohil.science.robot_description import MAX_FLOOR_M, RobotDescription
from odohil.science.targets import TARGET_FRACTIONS
from odohil.session.plan import parse_plan
from odohil.session.preflight import default_variant
from odohil.session.robot_file import load_robot_description

DEFAULT_SIGMA_M = 0.001
MIN_TRIALS_RANGE = RANGES["min_trials_per_design"]
MEASURE_S_RANGE = RANGES["measure_s"]
SPEED_RANGE = RANGES["speed"]
BUDGET_MIN_RANGE = RANGES["budget_min"]
DEFAULT_TARGETS_TEXT = (
    f"{TARGET_FRACTIONS['E_R']:.0%} of |E_R|, {TARGET_FRACTIONS['E_T']:.0%} of |E_T|, "
    f"{TARGET_FRACTIONS['K_theta']:.0%} of K_theta and K_rho (priors), with floors"
)


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


def _document(
    plan: Plan, prior: ErrorParameters, measurement: str, given: set[str]
) -> dict[str, object]:
    errors = {}
    for name, se in zip(PARAMETER_NAMES, plan.standard_errors, strict=True):
        target = plan.targets[name]
        errors[name] = {
            "stderr_si": float(se),
            "unit_si": SI_UNITS[name],
            "stderr_paper": units.parameter_to_paper(name, float(se)),
            "unit_paper": PAPER_UNITS[name],
            "target_si": target,
            "target_paper": units.parameter_to_paper(name, target),
            "target_source": "given" if name in given else "default",
            "ratio_to_target": float(se) / target,
        }
    return {
        "designs": [
            {
                "k": item.design.k,
                "l_m": item.design.l_m,
                "variant": item.design.variant,
                "n_trials": item.n_trials,
                "distance_m": item.distance_m,
                "minutes": item.n_trials * plan.operator.trial_seconds(item.design) / 60.0,
            }
            for item in plan.items
        ],
        "distance_m": plan.distance_m,
        "floor_needed_m": plan.excursion_m,
        "n_trials": plan.n_trials,
        "operator_minutes": plan.duration_s / 60.0,
        "operator_model": {
            "seconds_per_trial": plan.operator.seconds_per_trial,
            "speed_m_per_s": plan.operator.speed_m_per_s,
            "turn_rate_rad_per_s": plan.operator.turn_rate_rad_per_s,
        },
        "min_trials_per_design": plan.min_trials_per_design,
        "expected_stderr": errors,
        "criterion": plan.criterion,
        "meets_targets": plan.meets_targets,
        "unmet_targets": list(plan.unmet),
        "notes": list(plan.notes),
        "prior_si": prior.to_si_dict(),
        "measurement": measurement,
    }


def _print(
    plan: Plan,
    prior: ErrorParameters,
    measurement: str,
    title: str,
    given: set[str],
    system: units.UnitSystem,
) -> None:
    console = Console()
    designs = Table(title=title)
    for column in ("k", "l (m)", "variant", "trials", "metres", "minutes"):
        designs.add_column(column, justify="right")
    for item in plan.items:
        designs.add_row(
            f"{item.design.k:g}",
            f"{item.design.l_m:g}",
            item.design.variant,
            str(item.n_trials),
            f"{item.distance_m:g}",
            f"{item.n_trials * plan.operator.trial_seconds(item.design) / 60.0:.0f}",
        )
    console.print(designs)
    console.print(
        f"operator time: about {plan.duration_s / 60.0:.0f} min "
        f"({plan.operator.seconds_per_trial:g} s to mark and measure a trial, driving at "
        f"{plan.operator.speed_m_per_s:g} m/s)",
        highlight=False,
    )
    console.print(
        f"free floor needed: {plan.excursion_m:g} m (one-way trials alternate and come back)",
        highlight=False,
    )
    errors = Table(title="Expected standard errors (Cramer-Rao)", caption=measurement)
    for column in ("parameter", "prior", "stderr", "target", "unit"):
        errors.add_column(column, justify="left" if column in ("parameter", "unit") else "right")
    prior_si = prior.to_si_dict()
    for name, se in zip(PARAMETER_NAMES, plan.standard_errors, strict=True):
        target = plan.targets[name]
        ratio = float(se) / target
        source = "" if name in given else " default"
        errors.add_row(
            name,
            f"{units.parameter_in(name, prior_si[name], system):.4g}",
            f"{units.parameter_in(name, float(se), system):.3g}",
            f"{units.parameter_in(name, target, system):.3g}{source} ({ratio:.2f}x)",
            units.unit_column(name, system),
        )
    console.print(errors)
    if plan.meets_targets:
        console.print(
            f"The plan meets every target (largest stderr/target = {plan.criterion:.3f}).",
            highlight=False,
        )
    else:
        console.print(
            f"The plan does NOT meet the targets of {', '.join(plan.unmet)} (largest "
            f"stderr/target = {plan.criterion:.3f}); default targets: {DEFAULT_TARGETS_TEXT}.",
            highlight=False,
        )
    for note in plan.notes:
        console.print(f"[yellow]note:[/yellow] {note}", highlight=False)


def plan(
    budget_m: float | None = typer.Option(
        None,
        "--budget-m",
        callback=bounded("budget_m"),
        help="Most metres driven in all (needed unless --budget-min or --evaluate).",
    ),
    budget_min: float | None = typer.Option(
        None,
        "--budget-min",
        callback=bounded("budget_min"),
        help=f"Most operator minutes in all, {BUDGET_MIN_RANGE.text()} (see --measure-s).",
    ),
    evaluate: str | None = typer.Option(
        None,
        "--evaluate",
        help='Score this plan instead of searching, e.g. "k=1,l=6,n=30;k=20,l=0.5,n=30".',
    ),
    min_trials_per_design: int = typer.Option(
        DEFAULT_MIN_TRIALS_PER_DESIGN,
        "--min-trials-per-design",
        callback=bounded("min_trials_per_design"),
        help="Fewest trials of any design, for honest 95 % intervals (they cover from about "
        f"10; 5 is marginal), {MIN_TRIALS_RANGE.text()}.",
    ),
    measure_s: float = typer.Option(
        DEFAULT_SECONDS_PER_TRIAL,
        "--measure-s",
        callback=bounded("measure_s"),
        help=f"Seconds to mark and measure one trial, {MEASURE_S_RANGE.text()}.",
    ),
    speed: float = typer.Option(
        DEFAULT_SPEED_M_PER_S,
        "--speed",
        callback=bounded("speed"),
        help=f"Driving speed for the time estimate, m/s, {SPEED_RANGE.text()}.",
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
        typer.Option(
            "--robot",
            callback=robot_callback,
            help=ROBOT_HELP + " Gives screws, sigma_m, cross pairs, turns_exact.",
        ),
    ] = None,
    target_e_r: float | None = typer.Option(
        None,
        "--target-E-R",
        callback=bounded("target_E_R"),
        help="Wanted stderr, deg/m (default: 25 % of |prior|, at least 0.005).",
    ),
    target_e_t: float | None = typer.Option(
        None,
        "--target-E-T",
        callback=bounded("target_E_T"),
        help="Wanted stderr of E_T (default: 25 % of |prior|, at least 0.002).",
    ),
    target_k_theta: float | None = typer.Option(
        None,
        "--target-K-theta",
        callback=bounded("target_K_theta"),
        help="Wanted stderr, deg^2/m (default: 50 % of the prior).",
    ),
    target_k_rho: float | None = typer.Option(
        None,
        "--target-K-rho",
        callback=bounded("target_K_rho"),
        help="Wanted stderr, m (default: 50 % of the prior).",
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
        f"robot description's \\[floor] length_m, else {DEFAULT_FLOOR_M:g}).",
    ),
    as_json: bool = typer.Option(False, "--json", help="Print the plan as JSON."),
    units_choice: UnitsOption = UNITS_DEFAULT,
) -> None:
    """Recommend designs for a budget (or score one with --evaluate); print each
    parameter's expected stderr against its target, and the operator time.

    Priors are in the paper's units (default: the Nomad 150 values). Every
    parameter has a target: those not given default to a fraction of the
    prior (25 % of |E_R| and |E_T|, 50 % of K_theta and K_rho, with floors).
    The plan minimises the largest stderr/target ratio; every design gets at
    least --min-trials-per-design trials.
    """
    description, measurement = _measurement(sigma_m, robot)
    if evaluate is None and budget_m is None and budget_min is None:
        raise typer.BadParameter("give --budget-m (metres) or --budget-min, or --evaluate PLAN")
    if evaluate is not None and (budget_m is not None or budget_min is not None):
        raise typer.BadParameter("--evaluate scores a given plan: give no --budget-m/--budget-min")
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
    operator = OperatorTime(measure_s, speed, DEFAULT_TURN_RATE_RAD_PER_S)
    try:
        prior = ErrorParameters.from_paper_units(e_r, e_t, k_theta, k_rho)
        if evaluate is not None:
            try:
                written = parse_plan(evaluate, default_variant(description))
            except OdohilError as exc:
                raise typer.BadParameter(f"--evaluate: {exc}") from None
            warn_turns(Console(stderr=True), written, description)
            result = evaluate_plan(
                [(item.design, item.n_trials) for item in written.items],
                prior,
                description=description,
                targets=targets,
                min_trials_per_design=min_trials_per_design,
                operator=operator,
            )
            title = f"Your plan: {result.distance_m:g} m, {units.plural(result.n_trials, 'trial')}"
        else:
            if not math.isfinite(max_leg_m) or max_leg_m <= 0:
                raise typer.BadParameter(f"--max-leg-m must be a positive length, got {max_leg_m}")
            if floor_m is not None and (
                not math.isfinite(floor_m) or not 0 < floor_m <= MAX_FLOOR_M
            ):
                raise typer.BadParameter(
                    f"--floor-m must be a length in (0, {MAX_FLOOR_M:g}] m, got {floor_m}"
                )
            floor = floor_m if floor_m is not None else description.floor_length_m
            result = plan_experiment(
                prior,
                budget_m if budget_m is not None else math.inf,
                max_trials=max_trials,
                description=description,
                targets=targets,
                max_designs=max_designs,
                max_leg_m=max_leg_m,
                floor_m=floor,
                min_trials_per_design=min_trials_per_design,
                operator=operator,
                budget_s=None if budget_min is None else 60.0 * budget_min,
            )
            limits = [f"{budget_m:g} m" if budget_m is not None else "", ""]
            if budget_min is not None:
                limits[1] = f"{budget_min:g} min"
            title = (
                f"Recommended plan: {result.distance_m:g} m, "
                f"{units.plural(result.n_trials, 'trial')} "
                f"(budget {' and '.join(x for x in limits if x)})"
            )
    except OdohilError as exc:
        raise typer.BadParameter(str(exc)) from exc
    if as_json:
        typer.echo(json.dumps(_document(result, prior, measurement, set(targets)), indent=2))
    else:
        _print(result, prior, measurement, title, set(targets), unit_system(units_choice))


def register(app: typer.Typer) -> None:
    """Add ``plan`` to the ``odohil`` app."""
    app.command("plan")(plan)
