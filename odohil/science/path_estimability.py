"""What a plan of general paths can and cannot estimate, before any trial is driven.

:func:`plan_estimability` is the pre-flight's statement
(odohil/session/plans/checks.py): the parameters a plan identifies with their
expected standard errors, the others with the reason, and the problems that
leave no estimate at all. The scores are odohil/science/path_plans.py's.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from odohil import units
from odohil.science.parameters import PARAMETER_NAMES
from odohil.science.path_plans import (
    CONFOUNDED,
    RobotModel,
    Shape,
    acting,
    driven_items,
    score_plan,
    shape_path,
)


@dataclass(frozen=True)
class Estimability:
    """What trials of a plan can and cannot estimate, before any is driven.

    Attributes:
        turns_exact: whether the model has the four parameters only.
        estimable: the parameters the plan identifies.
        standard_errors: their expected (Cramer-Rao) standard errors, SI.
        not_estimable: (parameter, reason) of the others.
        notes: what else to know (near-confoundings, the model).
        problems: why no estimate could come of these trials (empty when one can).
    """

    turns_exact: bool
    estimable: tuple[str, ...]
    standard_errors: tuple[float, ...]
    not_estimable: tuple[tuple[str, str], ...]
    notes: tuple[str, ...] = ()
    problems: tuple[str, ...] = ()

    @property
    def ok(self) -> bool:
        """Whether an estimate can come of these trials."""
        return not self.problems

    def text(self, *, problems: bool = True) -> str:
        """The statement (expected standard errors in paper units), with the
        problems unless ``problems`` is False."""
        found = [
            f"{name} (SE {units.paper_text(name, se)})"
            for name, se in zip(self.estimable, self.standard_errors, strict=True)
        ]
        sentences = [f"Estimates {units.join_words(found) or 'nothing'}"]
        if not self.turns_exact and any(n not in PARAMETER_NAMES for n in self.estimable):
            sentences[0] += ", the turn errors with the four (not folded into E_R and K_theta)"
        if self.not_estimable:
            sentences.append(
                "Cannot estimate "
                + "; ".join(f"{name}: {reason}" for name, reason in self.not_estimable)
            )
        sentences += [*self.notes, *(self.problems if problems else ())]
        return ". ".join(sentences) + "."


def plan_estimability(items: Sequence[tuple[Shape, int]], robot: RobotModel) -> Estimability:
    """What a plan can estimate on ``robot`` (module docstring): the
    parameters it identifies with their expected standard errors, the others
    with the reason, and the problems that leave no estimate at all: one of
    the four not identified, a turn error that acts on the trials but is not
    identified (the estimator fits every turn error whose turns the trials
    make: odohil/science/estimators/paths.py), or no more trials than
    parameters.

    Raises:
        ParameterError: an empty plan or a negative count.
    """
    checked = driven_items(items)
    score = score_plan(checked, robot)
    acts = acting([shape_path(shape) for shape, _ in checked], robot)
    problems = [
        f"{p.name} is not identified: {p.reason}"
        for p in score.parameters
        if not p.estimable and p.name not in acts
    ]
    fitted = len(robot.names) - len(acts)
    n_trials = sum(n for _, n in checked)
    if n_trials <= fitted:
        problems.append(
            f"{units.plural(n_trials, 'trial')} for {fitted} parameters: need at least {fitted + 1}"
        )
    names = score.names
    corr = score.correlation
    notes = [
        f"{names[a]} and {names[b]} are nearly confounded (correlation {corr[a, b]:+.3f})"
        for a in range(len(names))
        for b in range(a + 1, len(names))
        if abs(corr[a, b]) > CONFOUNDED
    ]
    notes += _split_note(checked, robot)
    kept = [p for p in score.parameters if p.estimable]
    return Estimability(
        turns_exact=robot.turns_exact,
        estimable=tuple(p.name for p in kept),
        standard_errors=tuple(p.standard_error for p in kept),
        not_estimable=tuple((p.name, p.reason) for p in score.parameters if not p.estimable),
        notes=tuple(notes),
        problems=tuple(problems),
    )


def _split_note(items: Sequence[tuple[Shape, int]], robot: RobotModel) -> list[str]:
    """What one e_turn per direction would estimate, for a plan that turns
    both ways with one kind of turn (the estimator splits e_turn by direction
    when a likelihood-ratio test asks for it: odohil/science/estimators/paths.py)."""
    if robot.turns_exact or robot.split_directions:
        return []
    turned = sum((shape_path(shape).turns.total_abs_rad for shape, _ in items), np.zeros(4))
    if not ((turned[0] > 0 and turned[1] > 0) or (turned[2] > 0 and turned[3] > 0)):
        return []
    split = score_plan(items, replace(robot, split_directions=True))
    both = [
        p
        for p in split.parameters
        if p.name.startswith("e_turn") and not p.reason.startswith("the plan makes no")
    ]
    found = [
        f"{p.name} (SE {units.paper_text(p.name, p.standard_error)})" for p in both if p.estimable
    ]
    lost = [f"{p.name}: {p.reason}" for p in both if not p.estimable]
    text = "If the data ask for one e_turn per direction, the split fit estimates " + (
        units.join_words(found) or "none of them"
    )
    return [text + (f"; not {'; '.join(lost)}" if lost else "")]
