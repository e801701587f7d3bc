"""What general paths buy a calibration (issue 19): a request naming paths
in the ``--path`` syntax (odohil/science/path_designs.py), a time budget and
the robot, checked and turned into
:func:`odohil.science.path_plans.compare_with_paths`'s comparison, and the
comparison as a JSON document. The seam for a planning command (``odohil
plan`` with paths to compare); errors name the options such a command would
take (``--compare-paths``, ``--budget-min``, ``--robot``, ``--sigma-m``)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

from odohil import units
from odohil.errors import ParameterError
from odohil.science.fisher import default_description
from odohil.science.parameters import ErrorParameters
from odohil.science.path_designs import parse_path_design
from odohil.science.path_plans import (
    PathComparison,
    PlanScore,
    RobotModel,
    compare_with_paths,
)
from odohil.science.planner import (
    DEFAULT_MIN_TRIALS_PER_DESIGN,
    DEFAULT_SECONDS_PER_TRIAL,
    DEFAULT_SPEED_M_PER_S,
    DEFAULT_TURN_RATE_RAD_PER_S,
    OperatorTime,
)
from odohil.science.robot_description import RobotDescription
from odohil.session.planning import DEFAULT_SIGMA_M
from odohil.session.robot_file import load_robot_description


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
        "parameters": {
            p.name: {
                "stderr_si": _finite(p.standard_error),
                "stderr_paper": _finite(units.parameter_to_paper(p.name, p.standard_error)),
                "unit_paper": units.parameter_unit(p.name, "paper"),
                "estimable": p.estimable,
                "reason": p.reason,
                "note": p.note,
            }
            for p in score.parameters
        },
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
