"""What general paths (squares, circles) buy over forth-and-back plans.

:func:`compare_with_paths` compares, at the same operator time, the best
turn-free plan, the best forth-and-back plan and the best plan with the given
general shapes (each odohil/science/path_plan_search.py
:func:`~odohil.science.path_plan_search.best_plan`), and says per parameter
what the general shapes buy (:class:`PathComparison`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from odohil import units
from odohil.errors import ParameterError
from odohil.science.path_plan_search import best_plan, default_design_grid
from odohil.science.path_plans import PlanScore, RobotModel, Shape, describe_plan
from odohil.science.paths import Design, FloatArray
from odohil.science.planner import DEFAULT_MIN_TRIALS_PER_DESIGN, OperatorTime


@dataclass(frozen=True)
class Gain:
    """What general paths change for one parameter.

    Attributes:
        name: the parameter.
        turn_free, forth_and_back, with_paths: its standard error (SI) in
            each plan of the comparison (math.inf: not estimable).
        newly_estimable: the plan with general paths estimates it and no
            forth-and-back plan of the search does.
        ratio: forth-and-back's standard error over the general paths'
            (> 1: the general paths buy precision; nan when either is not estimable).
    """

    name: str
    turn_free: float
    forth_and_back: float
    with_paths: float

    @property
    def newly_estimable(self) -> bool:
        """Estimable only with the general paths."""
        return math.isinf(self.forth_and_back) and math.isfinite(self.with_paths)

    @property
    def ratio(self) -> float:
        """forth_and_back / with_paths (nan when either is not estimable)."""
        if math.isinf(self.forth_and_back) or math.isinf(self.with_paths):
            return math.nan
        return self.forth_and_back / self.with_paths


MIXED_DESIGNS = 2
"""Most forth-and-back designs beside the general shapes in a comparison's plan."""
BUYS_RATIO = 1.2
"""General paths buy precision in a parameter when they shrink its standard
error by at least this factor at the same time."""


@dataclass(frozen=True)
class PathComparison:
    """What adding general paths (squares, circles) buys over the best
    forth-and-back plans of the same operator time.

    Attributes:
        budget_s: the operator time of every plan, s.
        turn_free: the best plan of turn-free designs (``reverse``; what the
            planner recommends for a robot whose turns carry error).
        forth_and_back: the best forth-and-back plan, turn designs allowed
            (the turn errors estimated, not folded into E_R and K_theta).
        with_paths: the best plan with one or two of the general shapes and
            up to :data:`MIXED_DESIGNS` forth-and-back designs beside them.
        gains: per parameter, what the general paths change.
        findings: the comparison in sentences, paper units.
    """

    budget_s: float
    turn_free: PlanScore | None
    forth_and_back: PlanScore | None
    with_paths: PlanScore | None
    gains: tuple[Gain, ...]
    findings: tuple[str, ...]

    @property
    def buys(self) -> tuple[str, ...]:
        """The parameters the general paths make estimable, or estimate at
        least :data:`BUYS_RATIO` times more precisely."""
        return tuple(g.name for g in self.gains if g.newly_estimable or g.ratio >= BUYS_RATIO)


def compare_with_paths(
    robot: RobotModel,
    general: Sequence[Shape],
    budget_s: float,
    *,
    operator: OperatorTime | None = None,
    designs: Sequence[Design] | None = None,
    target_errors: FloatArray | None = None,
    min_trials: int = DEFAULT_MIN_TRIALS_PER_DESIGN,
    max_items: int = 3,
) -> PathComparison:
    """Compare, at the same operator time, the best turn-free plan, the best
    forth-and-back plan and the best plan that adds ``general`` shapes
    (:func:`best_plan` each), and say per parameter what the general shapes
    buy (module docstring; :class:`PathComparison`).

    Raises:
        ParameterError: no general shape or a bad budget.
    """
    if not general:
        raise ParameterError("the comparison needs at least one general path")
    grid = list(designs) if designs is not None else default_design_grid()

    def search(shapes: Sequence[Shape], required: Sequence[Shape] = ()) -> PlanScore | None:
        if not shapes:
            return None
        return best_plan(
            shapes,
            robot,
            budget_s,
            operator=operator,
            target_errors=target_errors,
            min_trials=min_trials,
            max_items=min(max_items, MIXED_DESIGNS) if required else max_items,
            required=required,
        )

    turn_free = search([d for d in grid if d.variant == "reverse"])
    forth = search(grid)
    mixed = search([*general, *grid], general)
    gains = tuple(
        Gain(
            name,
            _error_of(turn_free, name),
            _error_of(forth, name),
            _error_of(mixed, name),
        )
        for name in robot.names
    )
    return PathComparison(
        budget_s, turn_free, forth, mixed, gains, _findings(robot, turn_free, forth, mixed, gains)
    )


def _error_of(score: PlanScore | None, name: str) -> float:
    return math.inf if score is None else score.parameter(name).standard_error


def _ratio_words(ratio: float) -> str:
    if abs(ratio - 1.0) < 0.05:
        return "about the same"
    if ratio > 1.0:
        return f"{ratio:.2g} times smaller"
    return f"{1.0 / ratio:.2g} times larger"


def _findings(
    robot: RobotModel,
    turn_free: PlanScore | None,
    forth: PlanScore | None,
    mixed: PlanScore | None,
    gains: Sequence[Gain],
) -> tuple[str, ...]:
    out: list[str] = []
    for title, score in (
        ("turn-free forth-and-back", turn_free),
        ("forth-and-back with turns", forth),
        ("with the general paths", mixed),
    ):
        out.append(f"Best {title}: " + ("none fits" if score is None else describe_plan(score)))
    for gain in gains:
        name = gain.name
        parts: list[str] = []
        if turn_free is not None and math.isinf(gain.turn_free):
            reason = turn_free.parameter(name).reason
            parts.append(f"turn-free designs cannot estimate it: {reason}")
        if forth is not None:
            entry = forth.parameter(name)
            if entry.estimable:
                text = f"forth-and-back SE {units.paper_text(name, gain.forth_and_back)}"
                parts.append(text + (f", {entry.note}" if entry.note else ""))
            else:
                parts.append(f"no forth-and-back plan estimates it: {entry.reason}")
        if mixed is not None:
            entry = mixed.parameter(name)
            if entry.estimable:
                text = f"with the general paths SE {units.paper_text(name, gain.with_paths)}"
                if gain.newly_estimable:
                    text += ": estimable only with them"
                elif math.isfinite(gain.ratio):
                    text += f" ({_ratio_words(gain.ratio)})"
                parts.append(text + (f", {entry.note}" if entry.note else ""))
            else:
                parts.append(f"nor do the general paths: {entry.reason}")
        out.append(f"{name}: " + "; ".join(parts))
    return tuple(out)
