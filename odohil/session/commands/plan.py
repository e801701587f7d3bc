"""What ``odohil plan`` computes: a plan request checked and turned into a
recommended (or scored) plan through odohil/science/planner.py, and the plan
as its JSON document. Errors name the command's options."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

from odohil import units
from odohil.errors import OdohilError, ParameterError
from odohil.science.fisher import default_description
from odohil.science.parameters import PAPER_UNITS, PARAMETER_NAMES, SI_UNITS, ErrorParameters
from odohil.science.planner import (
    DEFAULT_MAX_LEG_M,
    DEFAULT_MIN_TRIALS_PER_DESIGN,
    DEFAULT_SECONDS_PER_TRIAL,
    DEFAULT_SPEED_M_PER_S,
    DEFAULT_TURN_RATE_RAD_PER_S,
    OperatorTime,
    Plan,
    evaluate_plan,
    plan_experiment,
)
from odohil.science.robot_description import MAX_FLOOR_M, RobotDescription
from odohil.science.targets import TARGET_FRACTIONS
from odohil.session.plans.checks import default_variant, turn_designs
from odohil.session.plans.plan import parse_plan
from odohil.session.robots.description import load_robot_description
from odohil.session.table_text import TableText

__all__ = [
    "DEFAULT_SIGMA_M",
    "PlanRequest",
    "PlannedExperiment",
    "plan_document",
]

DEFAULT_SIGMA_M = 0.001
"""Tape sigma of one floor-mark distance without a robot description, m."""
DEFAULT_TARGETS_TEXT = (
    f"{TARGET_FRACTIONS['E_R']:.0%} of |E_R|, {TARGET_FRACTIONS['E_T']:.0%} of |E_T|, "
    f"{TARGET_FRACTIONS['K_theta']:.0%} of K_theta and K_rho (priors), with floors"
)
"""The default targets in words."""


@dataclass(frozen=True)
class PlanRequest:
    """What ``odohil plan`` is asked (units as its options: targets in the
    paper's units, budgets in metres and minutes).

    Attributes:
        prior: the prior guess of the parameters.
        targets_paper: the wanted standard errors given, by parameter name.
        budget_m, budget_min: the budgets (None: not given).
        evaluate: a plan to score instead of searching (``--evaluate``).
        sigma_m, robot: the measurement: a tape sigma or a robot description.
        compare_paths: general paths to compare with forth-and-back plans of
            ``budget_min`` (``--compare-paths``; odohil/session/commands/plan_paths.py).
        split_directions: one e_turn per kind of turn and direction (plans
            with paths, the comparison).
    """

    prior: ErrorParameters
    targets_paper: dict[str, float | None] = field(default_factory=dict)
    budget_m: float | None = None
    budget_min: float | None = None
    evaluate: str | None = None
    sigma_m: float | None = None
    robot: Path | None = None
    min_trials_per_design: int = DEFAULT_MIN_TRIALS_PER_DESIGN
    measure_s: float = DEFAULT_SECONDS_PER_TRIAL
    speed_m_per_s: float = DEFAULT_SPEED_M_PER_S
    max_trials: int | None = None
    max_designs: int = 2
    max_leg_m: float = DEFAULT_MAX_LEG_M
    floor_m: float | None = None
    compare_paths: str | None = None
    split_directions: bool = False


@dataclass(frozen=True)
class PlannedExperiment:
    """A plan with what it was made from.

    Attributes:
        plan: the planner's result.
        prior: the prior parameters.
        measurement: how trials are measured, in words.
        title: a heading for people.
        given: the names of the targets the request gave.
        turn_designs: labels of turn designs on a robot whose turns carry
            error (the estimate would not be trusted).
    """

    plan: Plan
    prior: ErrorParameters
    measurement: str
    title: str
    given: frozenset[str]
    turn_designs: tuple[str, ...] = ()

    def design_rows(self) -> list[tuple[str, ...]]:
        """Per design: k, l (m), variant, trials, metres, operator minutes."""
        rows: list[tuple[str, ...]] = []
        for i, item in enumerate(self.plan.items):
            d = item.design
            minutes = f"{trial_minutes(self.plan, i):.0f}"
            row = (f"{d.k:g}", f"{d.l_m:g}", d.variant, str(item.n_trials), f"{item.distance_m:g}")
            rows.append((*row, minutes))
        return rows

    def designs_table(self) -> TableText:
        """The table of :meth:`design_rows` under the plan's title."""
        designs = ("k", "l (m)", "variant", "trials", "metres", "minutes")
        return TableText(self.title, designs, self.design_rows())

    def errors_table(self, system: units.UnitSystem) -> TableText:
        """The table of :meth:`error_rows`, the measurement below it."""
        columns = ("parameter", "prior", "stderr", "target", "unit")
        title = "Expected standard errors (Cramer-Rao)"
        rows = self.error_rows(system)
        return TableText(title, columns, rows, ("parameter", "unit"), self.measurement)

    def error_rows(self, system: units.UnitSystem) -> list[tuple[str, ...]]:
        """Per parameter in ``system``'s units: name, prior, expected standard
        error, target (" default" when not given; the stderr/target ratio), unit."""
        rows: list[tuple[str, ...]] = []
        prior_si, shown = self.prior.to_si_dict(), units.parameter_in
        for name, se in zip(PARAMETER_NAMES, self.plan.standard_errors, strict=True):
            target = self.plan.targets[name]
            source = "" if name in self.given else " default"
            rows.append(
                (
                    name,
                    f"{shown(name, prior_si[name], system):.4g}",
                    f"{shown(name, float(se), system):.3g}",
                    f"{shown(name, target, system):.3g}{source} ({float(se) / target:.2f}x)",
                    units.unit_column(name, system),
                )
            )
        return rows

    def turn_warning(self) -> str | None:
        """Why the plan's turn designs would not be trusted (None: it has none)."""
        if not self.turn_designs:
            return None
        return (
            f"turn designs on a robot whose turns carry error ({', '.join(self.turn_designs)}): "
            "the estimate will not be trusted; use variant=reverse"
        )

    def time_lines(self) -> list[str]:
        """The operator time and the free floor the plan needs."""
        plan, op = self.plan, self.plan.operator
        return [
            f"operator time: about {plan.duration_s / 60.0:.0f} min ({op.seconds_per_trial:g} s "
            f"to mark and measure a trial, driving at {op.speed_m_per_s:g} m/s)",
            f"free floor needed: {plan.excursion_m:g} m (one-way trials alternate and come back)",
        ]

    def verdict(self) -> str:
        """Whether the plan meets every target (the largest stderr/target)."""
        plan = self.plan
        if plan.meets_targets:
            return f"The plan meets every target (largest stderr/target = {plan.criterion:.3f})."
        return (
            f"The plan does NOT meet the targets of {', '.join(plan.unmet)} (largest "
            f"stderr/target = {plan.criterion:.3f}); default targets: {DEFAULT_TARGETS_TEXT}."
        )


def measurement_of(request: PlanRequest) -> tuple[RobotDescription, str]:
    """The robot description of ``--robot`` or ``--sigma-m``, and the measurement in words.

    Raises:
        ParameterError: both given, or a bad sigma.
    """
    if request.sigma_m is not None and request.robot is not None:
        raise ParameterError("give either --sigma-m or --robot, not both")
    if request.robot is not None:
        return load_robot_description(request.robot), f"robot description {request.robot}"
    sigma = DEFAULT_SIGMA_M if request.sigma_m is None else request.sigma_m
    if not math.isfinite(sigma) or sigma <= 0:
        raise ParameterError(f"--sigma-m must be a positive number of metres, got {sigma}")
    return default_description(sigma), (
        f"tape sigma {sigma:g} m, screws on a 0.2 m radius circle, one cross distance"
    )


def targets_of(request: PlanRequest) -> dict[str, float]:
    """The targets given, SI, by parameter name (ParameterError: one not positive)."""
    for name, value in request.targets_paper.items():
        if value is not None and (not math.isfinite(value) or value <= 0):
            raise ParameterError(f"--target-{name.replace('_', '-')} must be positive")
    given = {n: v for n, v in request.targets_paper.items() if v is not None}
    return {n: units.parameter_from_paper(n, v) for n, v in given.items()}


def make_plan(request: PlanRequest) -> PlannedExperiment:
    """The recommended plan for the budgets, or the ``--evaluate`` plan scored.

    Raises:
        ParameterError: budgets and ``--evaluate`` both or neither, a bad
            sigma, target, leg, floor or plan (naming the option).
        OdohilError: the planner finds no plan (e.g. no candidate design).
    """
    description, measurement = measurement_of(request)
    budget = request.budget_m is not None or request.budget_min is not None
    if request.evaluate is None and not budget:
        raise ParameterError("give --budget-m (metres) or --budget-min, or --evaluate PLAN")
    if request.evaluate is not None and budget:
        raise ParameterError("--evaluate scores a given plan: give no --budget-m/--budget-min")
    targets = targets_of(request)
    operator = OperatorTime(request.measure_s, request.speed_m_per_s, DEFAULT_TURN_RATE_RAD_PER_S)
    prior = request.prior
    turns: list[str] = []
    if request.evaluate is not None:
        try:
            written = parse_plan(request.evaluate, default_variant(description))
        except OdohilError as exc:
            raise ParameterError(f"--evaluate: {exc}") from None
        if written.has_paths:
            raise ParameterError(
                f"--evaluate {written.to_text()}: the planner scores forth-and-back designs; "
                "a plan with general paths (path=...) is run as given"
            )
        turns = turn_designs(written, description)
        plan = evaluate_plan(
            list(written.line_items),
            prior,
            description=description,
            targets=targets,
            min_trials_per_design=request.min_trials_per_design,
            operator=operator,
        )
        title = f"Your plan: {plan.distance_m:g} m, {units.plural(plan.n_trials, 'trial')}"
    else:
        if not math.isfinite(request.max_leg_m) or request.max_leg_m <= 0:
            raise ParameterError(f"--max-leg-m must be a positive length, got {request.max_leg_m}")
        floor_m = request.floor_m
        if floor_m is not None and (not math.isfinite(floor_m) or not 0 < floor_m <= MAX_FLOOR_M):
            raise ParameterError(
                f"--floor-m must be a length in (0, {MAX_FLOOR_M:g}] m, got {floor_m}"
            )
        budget_min = request.budget_min
        plan = plan_experiment(
            prior,
            request.budget_m if request.budget_m is not None else math.inf,
            max_trials=request.max_trials,
            max_designs=request.max_designs,
            max_leg_m=request.max_leg_m,
            floor_m=floor_m if floor_m is not None else description.floor_length_m,
            budget_s=None if budget_min is None else 60.0 * budget_min,
            description=description,
            targets=targets,
            min_trials_per_design=request.min_trials_per_design,
            operator=operator,
        )
        limits = [f"{request.budget_m:g} m" if request.budget_m is not None else ""]
        limits.append(f"{budget_min:g} min" if budget_min is not None else "")
        title = (
            f"Recommended plan: {plan.distance_m:g} m, {units.plural(plan.n_trials, 'trial')} "
            f"(budget {' and '.join(x for x in limits if x)})"
        )
    return PlannedExperiment(plan, prior, measurement, title, frozenset(targets), tuple(turns))


def trial_minutes(plan: Plan, index: int) -> float:
    """Operator minutes of the plan's ``index``-th design (all its trials)."""
    item = plan.items[index]
    return item.n_trials * plan.operator.trial_seconds(item.design) / 60.0


def plan_document(planned: PlannedExperiment) -> dict[str, object]:
    """The JSON document of ``odohil plan --json`` (SI, with the paper's units beside)."""
    plan = planned.plan
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
            "target_source": "given" if name in planned.given else "default",
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
                "minutes": trial_minutes(plan, i),
            }
            for i, item in enumerate(plan.items)
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
        "prior_si": planned.prior.to_si_dict(),
        "measurement": planned.measurement,
    }
