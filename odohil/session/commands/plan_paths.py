"""``odohil plan`` with general paths (issue 19): a plan naming paths scored
(``--evaluate``: :func:`odohil.science.path_plans.score_plan` with the turn
errors when the robot's turns carry error), and a request naming paths in the
``--path`` syntax (odohil/science/path_designs.py), a time budget and the
robot, checked and turned into
:func:`odohil.science.path_comparison.compare_with_paths`'s comparison
(``--compare-paths``); each with its JSON document and its text.
:func:`plan_outcome` is the plan command's one entry: it hands plans of
forth-and-back designs and budgets to odohil/session/commands/plan.py. Errors
name the options (``--compare-paths``, ``--budget-min``, ``--robot``,
``--sigma-m``, ``--evaluate``)."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from pathlib import Path

from odohil import units
from odohil.errors import OdohilError, ParameterError
from odohil.science.fisher import default_description
from odohil.science.parameters import ErrorParameters
from odohil.science.path_comparison import BUYS_RATIO, PathComparison, compare_with_paths
from odohil.science.path_designs import parse_path_design
from odohil.science.path_estimability import plan_estimability
from odohil.science.path_plan_search import default_targets
from odohil.science.path_plans import PlanScore, RobotModel, describe_plan, score_plan
from odohil.science.planner import (
    DEFAULT_MIN_TRIALS_PER_DESIGN,
    DEFAULT_SECONDS_PER_TRIAL,
    DEFAULT_SPEED_M_PER_S,
    DEFAULT_TURN_RATE_RAD_PER_S,
    OperatorTime,
)
from odohil.science.robot_description import RobotDescription
from odohil.session.commands.plan import (
    DEFAULT_SIGMA_M,
    PlannedExperiment,
    PlanRequest,
    make_plan,
    measurement_of,
    targets_of,
)
from odohil.session.plans.checks import default_variant, plan_items
from odohil.session.plans.plan import parse_plan
from odohil.session.robots.description import load_robot_description
from odohil.session.table_text import TableText


@dataclass(frozen=True)
class PathComparisonRequest:
    """A comparison asked for (units as a command's options).

    Attributes:
        paths: the general paths, ``;``-separated in the ``--path`` syntax
            (e.g. ``square:1,cw;square:1,ccw``).
        budget_min: the operator time of every plan compared, minutes.
        robot: a robot description file (its priors, turns_exact, floor
            marks); None: ``sigma_m`` with the default layout, turns exact.
        sigma_m: the tape sigma without a robot description, m.
        prior: the parameters the information is evaluated at (None: the
            description's ``[priors]``, or the paper's defaults).
        split_directions: one e_turn per kind and direction.
        measure_s, speed_m_per_s: the time model (odohil/science/planner.py OperatorTime).
        min_trials: fewest trials of any item.
    """

    paths: str
    budget_min: float
    robot: Path | None = None
    sigma_m: float | None = None
    prior: ErrorParameters | None = None
    split_directions: bool = False
    measure_s: float = DEFAULT_SECONDS_PER_TRIAL
    speed_m_per_s: float = DEFAULT_SPEED_M_PER_S
    min_trials: int = DEFAULT_MIN_TRIALS_PER_DESIGN


def _description(request: PathComparisonRequest) -> RobotDescription:
    if request.sigma_m is not None and request.robot is not None:
        raise ParameterError("give either --sigma-m or --robot, not both")
    if request.robot is not None:
        return load_robot_description(request.robot)
    sigma = DEFAULT_SIGMA_M if request.sigma_m is None else request.sigma_m
    if not math.isfinite(sigma) or sigma <= 0:
        raise ParameterError(f"--sigma-m must be a positive number of metres, got {sigma}")
    return default_description(sigma)


def compare_paths(request: PathComparisonRequest) -> PathComparison:
    """The comparison of the request (module docstring).

    Raises:
        ParameterError: no path, a path not in the syntax, a bad budget or
            sigma (naming the option).
        RobotDescriptionError: the robot description cannot be read.
    """
    texts = [t.strip() for t in request.paths.split(";") if t.strip()]
    if not texts:
        raise ParameterError(
            "--compare-paths: give one or more paths, e.g. square:1,cw;square:1,ccw"
        )
    try:
        shapes = [parse_path_design(text) for text in texts]
    except ParameterError as exc:
        raise ParameterError(f"--compare-paths: {exc}") from None
    if not (math.isfinite(request.budget_min) and request.budget_min > 0):
        raise ParameterError(f"--budget-min must be a positive number, got {request.budget_min}")
    description = _description(request)
    model = RobotModel.of(description, split_directions=request.split_directions)
    if request.prior is not None:
        model = RobotModel(
            request.prior,
            model.turns_exact,
            model.turns,
            model.split_directions,
            description=description,
        )
    operator = OperatorTime(request.measure_s, request.speed_m_per_s, DEFAULT_TURN_RATE_RAD_PER_S)
    return compare_with_paths(
        model, shapes, 60.0 * request.budget_min, operator=operator, min_trials=request.min_trials
    )


def _finite(value: float) -> float | None:
    return value if math.isfinite(value) else None


def _plan(score: PlanScore | None) -> dict[str, object] | None:
    if score is None:
        return None
    return {
        "items": [
            {"shape": label, "n_trials": n}
            for label, n in zip(score.labels, score.counts, strict=True)
        ],
        "operator_minutes": score.seconds / 60.0,
        "distance_m": score.distance_m,
        "parameters": _parameters(score),
    }


def _parameters(score: PlanScore) -> dict[str, dict[str, object]]:
    return {
        p.name: {
            "stderr_si": _finite(p.standard_error),
            "stderr_paper": _finite(units.parameter_to_paper(p.name, p.standard_error)),
            "unit_paper": units.parameter_unit(p.name, "paper"),
            "estimable": p.estimable,
            "reason": p.reason,
            "note": p.note,
        }
        for p in score.parameters
    }


def comparison_document(found: PathComparison) -> dict[str, object]:
    """The comparison as JSON: each plan (items, minutes, per parameter the
    standard error in SI and paper units or null, and why not), per
    parameter what the general paths change, what they buy, and the findings."""
    return {
        "budget_min": found.budget_s / 60.0,
        "turn_free": _plan(found.turn_free),
        "forth_and_back": _plan(found.forth_and_back),
        "with_paths": _plan(found.with_paths),
        "gains": {
            g.name: {
                "turn_free_si": _finite(g.turn_free),
                "forth_and_back_si": _finite(g.forth_and_back),
                "with_paths_si": _finite(g.with_paths),
                "newly_estimable": g.newly_estimable,
                "ratio": None if math.isnan(g.ratio) else g.ratio,
            }
            for g in found.gains
        },
        "buys": list(found.buys),
        "findings": list(found.findings),
    }


def comparison_lines(found: PathComparison) -> list[str]:
    """The comparison for people: what the general paths buy over the best
    forth-and-back plan of the same time, then the findings (the three plans,
    and per parameter its standard errors, paper units)."""
    minutes = f"{found.budget_s / 60.0:g} min"
    bought = ", ".join(found.buys) or (
        f"nothing (no parameter newly estimable or {BUYS_RATIO:g} times more precise)"
    )
    return [
        f"What the general paths buy over the best forth-and-back plan of {minutes}: {bought}.",
        *found.findings,
    ]


@dataclass(frozen=True)
class ScoredPaths:
    """A plan naming general paths, scored (``odohil plan --evaluate``).

    Attributes:
        plan: the plan in the ``--plan`` syntax.
        score: per parameter its expected (Cramer-Rao) standard error, SI, or
            why the plan cannot estimate it; the operator time and metres.
        targets: per parameter (``score.names``) the wanted standard error, SI.
        given: the names of the targets the request gave.
        measurement: how trials are measured, in words.
        notes: near-confoundings, what a split fit would estimate, the model.
        problems: why no estimate could come of these trials (empty when one can).
    """

    plan: str
    score: PlanScore
    targets: tuple[float, ...]
    given: frozenset[str]
    measurement: str
    notes: tuple[str, ...]
    problems: tuple[str, ...]

    @property
    def title(self) -> str:
        """A heading for people."""
        trials = units.plural(sum(self.score.counts), "trial")
        return f"Your plan: {describe_plan(self.score)}, {self.score.distance_m:g} m, {trials}"

    def rows(self, system: units.UnitSystem) -> list[tuple[str, str, str, str]]:
        """Per parameter: name, standard error, target (and the ratio), unit."""
        out = []
        for p, target in zip(self.score.parameters, self.targets, strict=True):
            source = "" if p.name in self.given else " default"
            shown = f"{units.parameter_in(p.name, target, system):.3g}{source}"
            if p.estimable:
                se = f"{units.parameter_in(p.name, p.standard_error, system):.3g}"
                shown += f" ({p.standard_error / target:.2f}x)"
            else:
                se = "not estimable"
            out.append((p.name, se, shown, units.unit_column(p.name, system)))
        return out

    def table(self, system: units.UnitSystem) -> TableText:
        """The table of :meth:`rows`, the measurement below it."""
        columns, words = ("parameter", "stderr", "target", "unit"), ("parameter", "unit")
        return TableText(self.title, columns, self.rows(system), words, self.measurement)

    def lines(self) -> list[str]:
        """What the plan cannot estimate and why, the notes and the problems."""
        cannot = [f"Cannot estimate {p.name}: {p.reason}." for p in self.score.parameters
                  if not p.estimable]  # fmt: skip
        return [*cannot, *(f"{n}." for n in self.notes), *(f"{p}." for p in self.problems)]


def _score_paths(request: PlanRequest, description: RobotDescription, plan: str) -> ScoredPaths:
    written = parse_plan(plan, default_variant(description))
    robot = replace(
        RobotModel.of(description, split_directions=request.split_directions),
        params=request.prior,
    )
    items = plan_items(written)
    operator = OperatorTime(request.measure_s, request.speed_m_per_s, DEFAULT_TURN_RATE_RAD_PER_S)
    score = score_plan(items, robot, operator)
    statement = plan_estimability(items, robot)
    given = targets_of(request)
    targets = tuple(
        given.get(name, float(default))
        for name, default in zip(robot.names, default_targets(robot), strict=True)
    )
    notes = list(statement.notes)
    if not robot.turns_exact:
        notes.append(
            "The turn errors are estimated with the four (the robot's turns carry error); "
            f"evaluated at e_turn {robot.turns.scales[0]:.2%} and K_spin "
            f"{units.paper_text('K_spin', robot.turns.k_spin)}"
        )
    _, measurement = measurement_of(request)
    return ScoredPaths(
        written.to_text(),
        score,
        targets,
        frozenset(given),
        measurement,
        tuple(notes),
        statement.problems,
    )


def plan_outcome(request: PlanRequest) -> PlannedExperiment | ScoredPaths | PathComparison:
    """What ``odohil plan`` answers: the comparison of ``--compare-paths``,
    a plan naming paths scored (``--evaluate``), else
    :func:`odohil.session.commands.plan.make_plan`'s plan.

    Raises:
        ParameterError: options that do not go together, a bad plan, path,
            budget, sigma or target (naming the option).
        OdohilError: the planner finds no plan; the robot description cannot be read.
    """
    if request.compare_paths is not None:
        if request.evaluate is not None:
            raise ParameterError("give either --compare-paths or --evaluate, not both")
        if request.budget_m is not None:
            raise ParameterError(
                "--compare-paths compares plans of the same operator time: "
                "give --budget-min, not --budget-m"
            )
        if request.budget_min is None:
            raise ParameterError(
                "--compare-paths needs --budget-min (the operator minutes of every plan compared)"
            )
        return compare_paths(
            PathComparisonRequest(
                request.compare_paths,
                request.budget_min,
                request.robot,
                request.sigma_m,
                request.prior,
                request.split_directions,
                request.measure_s,
                request.speed_m_per_s,
                request.min_trials_per_design,
            )
        )
    if request.evaluate is None:
        return make_plan(request)
    description, _ = measurement_of(request)
    try:
        paths = parse_plan(request.evaluate, default_variant(description)).has_paths
    except OdohilError as exc:
        raise ParameterError(f"--evaluate: {exc}") from None
    if not paths:
        return make_plan(request)
    if request.budget_m is not None or request.budget_min is not None:
        raise ParameterError("--evaluate scores a given plan: give no --budget-m/--budget-min")
    return _score_paths(request, description, request.evaluate)


def scored_document(scored: ScoredPaths) -> dict[str, object]:
    """The JSON document of ``odohil plan --evaluate`` for a plan naming paths:
    its items, minutes and metres, per parameter the standard error (SI and
    paper units, null when not estimable, and why), its target, and the
    notes and problems."""
    parameters = _parameters(scored.score)
    for p, target in zip(scored.score.parameters, scored.targets, strict=True):
        parameters[p.name] |= {
            "target_si": target,
            "target_paper": units.parameter_to_paper(p.name, target),
            "target_source": "given" if p.name in scored.given else "default",
            "ratio_to_target": p.standard_error / target if p.estimable else None,
        }
    return {
        "plan": scored.plan,
        **(_plan(scored.score) or {}),
        "parameters": parameters,
        "n_trials": sum(scored.score.counts),
        "estimable": list(scored.score.estimable),
        "notes": list(scored.notes),
        "problems": list(scored.problems),
        "measurement": scored.measurement,
    }


PathsOutcome = ScoredPaths | PathComparison
"""What :func:`plan_outcome` gives besides a plan of forth-and-back designs."""


def paths_document(found: PathsOutcome) -> dict[str, object]:
    """The JSON document of a plan naming paths or of a comparison."""
    if isinstance(found, ScoredPaths):
        return scored_document(found)
    return comparison_document(found)


def paths_lines(found: PathsOutcome) -> list[str]:
    """The sentences for people of a plan naming paths (after its table) or of a comparison."""
    return found.lines() if isinstance(found, ScoredPaths) else comparison_lines(found)
