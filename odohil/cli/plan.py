"""``odohil plan``: recommend calibration designs for a budget (the work is
odohil/session/commands/plan.py's)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console

from odohil import units
from odohil.cli.options import (
    UNITS_DEFAULT,
    JsonOption,
    Parameters,
    UnitsOption,
    option,
    parameters_option,
    robot_option,
    unit_system,
    usage_errors,
)
from odohil.cli.render import drawn
from odohil.science.limits import RANGES
from odohil.science.planner import (
    DEFAULT_FLOOR_M,
    DEFAULT_MAX_LEG_M,
    DEFAULT_MIN_TRIALS_PER_DESIGN,
    DEFAULT_SECONDS_PER_TRIAL,
    DEFAULT_SPEED_M_PER_S,
    MAX_DESIGNS,
)
from odohil.science.robot_description import MAX_FLOOR_M
from odohil.session.commands import plan_paths as paths
from odohil.session.commands.plan import (
    DEFAULT_SIGMA_M,
    PlannedExperiment,
    PlanRequest,
    plan_document,
)

Metres = Annotated[float | None, option("--budget-m", bound="budget_m", help="Most metres "
                   "driven in all (needed unless --budget-min or --evaluate).")]  # fmt: skip


def _print(planned: PlannedExperiment, system: units.UnitSystem) -> None:
    console = Console()
    console.print(drawn(planned.designs_table()))
    for text in planned.time_lines():
        console.print(text, highlight=False)
    console.print(drawn(planned.errors_table(system)))
    console.print(planned.verdict(), highlight=False)
    for note in planned.plan.notes:
        console.print(f"[yellow]note:[/yellow] {note}", highlight=False)


def _print_paths(found: paths.PathsOutcome, as_json: bool, system: units.UnitSystem) -> None:
    if as_json:
        return typer.echo(json.dumps(paths.paths_document(found), indent=2))
    if isinstance(found, paths.ScoredPaths):
        Console().print(drawn(found.table(system)))
    for line in paths.paths_lines(found):
        Console().print(line, highlight=False, markup=False)


@parameters_option
def plan(
    budget_m: Metres = None,
    budget_min: Annotated[float | None, option("--budget-min", bound="budget_min", help="Most "
        f"operator minutes in all, {RANGES['budget_min'].text()} (see --measure-s).")] = None,
    evaluate: Annotated[str | None, option("--evaluate", help="Score this plan instead of "
        'searching, e.g. "k=1,l=6,n=30;k=20,l=0.5,n=30"; with paths (path=square:1,cw,n=10) '
        "the turn errors too, unless the robot's turns are exact.")] = None,
    compare: Annotated[str | None, option("--compare-paths", help='What paths (e.g. "square:1,'
        'cw;square:1,ccw") buy over forth-and-back plans of --budget-min.')] = None,
    split: Annotated[bool, typer.Option("--split-directions", help="Paths: one turn error "
        "per kind of turn and direction.")] = False,
    min_trials_per_design: Annotated[int, option("--min-trials-per-design",
        bound="min_trials_per_design", help="Fewest trials of any design, for honest 95 % "
        "intervals (they cover from about 10; 5 is marginal), "
        f"{RANGES['min_trials_per_design'].text()}.")] = DEFAULT_MIN_TRIALS_PER_DESIGN,
    measure_s: Annotated[float, option("--measure-s", bound="measure_s", help="Seconds to mark "
        f"and measure one trial, {RANGES['measure_s'].text()}.")] = DEFAULT_SECONDS_PER_TRIAL,
    speed: Annotated[float, option("--speed", bound="speed", help="Driving speed for the time "
        f"estimate, m/s, {RANGES['speed'].text()}.")] = DEFAULT_SPEED_M_PER_S,
    max_trials: Annotated[int | None, option("--max-trials", bound="max_trials",
        help="Most trials in all (each is marked and measured).")] = None,
    sigma_m: Annotated[float | None, option("--sigma-m", bound="sigma_m", help="Tape sigma of "
        f"one floor-mark distance, m (default {DEFAULT_SIGMA_M}), with three screws on a "
        "0.2 m radius circle and one cross distance.")] = None,
    robot: Annotated[Path | None, robot_option(" Gives screws, sigma_m, cross pairs, "
        "turns_exact.")] = None,
    target_e_r: Annotated[float | None, option("--target-E-R", bound="target_E_R",
        help="Wanted stderr, deg/m (default: 25 % of |prior|, at least 0.005).")] = None,
    target_e_t: Annotated[float | None, option("--target-E-T", bound="target_E_T",
        help="Wanted stderr of E_T (default: 25 % of |prior|, at least 0.002).")] = None,
    target_k_theta: Annotated[float | None, option("--target-K-theta", bound="target_K_theta",
        help="Wanted stderr, deg^2/m (default: 50 % of the prior).")] = None,
    target_k_rho: Annotated[float | None, option("--target-K-rho", bound="target_K_rho",
        help="Wanted stderr, m (default: 50 % of the prior).")] = None,
    max_designs: Annotated[int, option("--max-designs", bound="max_designs",
        help=f"Mix at most this many designs (1 to {MAX_DESIGNS}).")] = 2,
    max_leg_m: Annotated[float, option("--max-leg-m", bound="max_leg_m",
        help="Longest leg the floor allows, m.")] = DEFAULT_MAX_LEG_M,
    floor_m: Annotated[float | None, option("--floor-m", help="Free floor along the line of "
        f"travel, m, (0, {MAX_FLOOR_M:g}] (default: the robot description's \\[floor] "
        f"length_m, else {DEFAULT_FLOOR_M:g}).")] = None,
    as_json: JsonOption = False,
    units_choice: UnitsOption = UNITS_DEFAULT,
    *,
    params: Parameters,
) -> None:  # fmt: skip
    """Recommend designs for a budget (or score one with --evaluate); print each
    parameter's expected stderr against its target, and the operator time.

    Priors (--E-R, --E-T, --K-theta, --K-rho) are in the paper's units
    (default: the Nomad 150 values). Every
    parameter has a target: those not given default to a fraction of the
    prior (25 % of |E_R| and |E_T|, 50 % of K_theta and K_rho, with floors).
    The plan minimises the largest stderr/target ratio; every design gets at
    least --min-trials-per-design trials. A plan naming general paths
    (--evaluate "path=square:1,cw,n=10;...") is scored with the robot's turn
    errors; --compare-paths says what paths buy over forth-and-back plans.
    """
    targets = {"E_R": target_e_r, "E_T": target_e_t, "K_theta": target_k_theta,
               "K_rho": target_k_rho}  # fmt: skip
    request = PlanRequest(params, targets, budget_m, budget_min, evaluate,
                          sigma_m, robot, min_trials_per_design, measure_s, speed, max_trials,
                          max_designs, max_leg_m, floor_m, compare, split)  # fmt: skip
    with usage_errors():
        planned = paths.plan_outcome(request)
    if not isinstance(planned, PlannedExperiment):
        return _print_paths(planned, as_json, unit_system(units_choice))
    if (warning := planned.turn_warning()) is not None:
        Console(stderr=True).print(f"[yellow]warning:[/] {warning}", soft_wrap=True)
    if as_json:
        typer.echo(json.dumps(plan_document(planned), indent=2))
    else:
        _print(planned, unit_system(units_choice))


def register(app: typer.Typer) -> None:
    """Add ``plan`` to the ``odohil`` app."""
    app.command("plan")(plan)
