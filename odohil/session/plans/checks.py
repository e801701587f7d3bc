"""Pre-flight checks of a session's inputs, made before any session folder is
created or any port opened: the plan against what the robot does. The
session folder's check is in odohil/session/run/checks.py (the ordered
list that every command runs), a trial file's in
odohil/session/trials/pose_file.py.

Every check raises an :class:`~odohil.errors.OdohilError` whose message names
the option or file and what is accepted; nothing has moved yet.

A plan must also fit the free floor (:func:`check_floor`): the robot drives
along one line; one-way trials alternate direction
(:func:`odohil.science.paths.floor_choreography`), so a plan needs as much free
floor as the span its trials cover (:attr:`Plan.excursion_m`). With ``[floor]
length_m`` in the robot description, a plan that needs more is refused. A
general path (a square, a polygon, a circle) is closed: it adds nothing to the
line's span; its floor need is its bounding box around the start mark
(:func:`~odohil.session.plans.plan.path_floor_m`), whose longer side must fit
the given length too.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

from odohil import units
from odohil.errors import ParameterError
from odohil.science.estimators.checks import plan_problems
from odohil.science.path_designs import PathDesign
from odohil.science.path_estimability import Estimability, plan_estimability
from odohil.science.path_plans import RobotModel, Shape, acting, shape_label, shape_path
from odohil.science.paths import Design
from odohil.science.planner import DEFAULT_MIN_TRIALS_PER_DESIGN
from odohil.science.robot_description import RobotDescription
from odohil.session.plans.plan import Plan, path_floor_m

FLOOR_SLACK_M = 1e-9
"""Rounding allowance when comparing the needed floor with the given one, metres."""


def check_floor(plan: Plan, description: RobotDescription) -> None:
    """Refuse a plan that needs more floor than ``[floor] length_m`` gives.

    Raises:
        ParameterError: names the first design (1-based, as in ``--plan``)
            whose trials take the robot beyond the floor, the floor it needs
            and the length given.
    """
    floor = description.floor_length_m
    if floor is None or plan.excursion_m <= floor + FLOOR_SLACK_M:
        return
    for number, item in enumerate(plan.items, start=1):
        design = item.design
        if isinstance(design, PathDesign):
            along, across = path_floor_m(design)
            if max(along, across) > floor + FLOOR_SLACK_M:
                raise ParameterError(
                    f"plan design {number} ({design.label()}) is a closed path that needs a "
                    f"{along:.3g} m x {across:.3g} m box of floor around its start mark, but the "
                    f"robot description's [floor] length_m is {floor:g} m: make the path "
                    "smaller or give a longer floor"
                )
            continue
        needed = Plan(plan.items[:number], plan.alternate).choreography.excursion_m
        if needed > floor + FLOOR_SLACK_M:
            raise ParameterError(
                f"plan design {number} ({design.label()}) takes the robot over {needed:g} m "
                f"of floor, but the robot description's [floor] length_m is {floor:g} m: "
                "shorten l (or the designs before it) or give a longer floor"
            )
    raise AssertionError("unreachable")


def default_variant(description: RobotDescription) -> str:
    """``turn`` for a robot whose in-place turns are exact, else ``reverse``."""
    return "turn" if description.robot.turns_exact else "reverse"


def turn_designs(plan: Plan, description: RobotDescription) -> list[str]:
    """Labels of the plan's forth-and-back ``turn`` designs when the robot's
    turns carry error (``[robot] turns_exact = false``) and the plan names no
    path; empty otherwise: a plan naming a path is estimated from general
    paths with the turn errors (:func:`estimability`), its turn designs too."""
    if description.robot.turns_exact or not designs_only(plan_items(plan)):
        return []
    return [d.label() for d, _ in plan.line_items if d.variant == "turn"]


def turn_warning(plan: Plan, description: RobotDescription) -> str | None:
    """What to say when the plan turns in place on a robot whose turns carry
    error (allowed with ``--allow-turns``); None when it does not."""
    turns = turn_designs(plan, description)
    if not turns:
        return None
    return (
        f"turn designs on a robot whose turns carry error ({', '.join(turns)}): "
        "the estimate will not be trusted; use variant=reverse"
    )


def check_turns(plan: Plan, description: RobotDescription, allow_turns: bool) -> None:
    """Refuse ``turn`` designs on a robot whose turns carry error, unless
    ``allow_turns`` (ParameterError naming ``--plan`` and ``--allow-turns``)."""
    turns = turn_designs(plan, description)
    if turns and not allow_turns:
        raise ParameterError(
            f"--plan asks for in-place turns ({', '.join(turns)}) but this robot's turns "
            "carry error ([robot] turns_exact = false): turn trials bias E_R and K_theta "
            "while looking consistent. Use variant=reverse (the default for this robot), "
            "or give --allow-turns to run them anyway (the estimate is then not trusted)"
        )


FOLDED_TURNS = (
    "Forth-and-back sessions are estimated with the four parameters, so the turn "
    "designs' spin errors fold into E_R and K_theta and the verdict is doubtful; to "
    "estimate the turn errors, name the turns as paths (e.g. path=square:1.0,cw,n=10)"
)
"""What the statement adds for ``turn`` designs on a robot whose turns carry error."""


def plan_items(plan: Plan) -> list[tuple[Shape, int]]:
    """The plan's (shape, number of trials): forth-and-back designs and paths."""
    return [(item.design, item.n_trials) for item in plan.items]


def designs_only(items: Sequence[tuple[Shape, int]]) -> bool:
    """Whether every item is a forth-and-back design (the session estimates
    such a plan with the four parameters; one naming a path from general
    paths, with the turn errors unless the robot's turns are exact)."""
    return all(isinstance(shape, Design) for shape, _ in items)


def estimability(items: Sequence[tuple[Shape, int]], description: RobotDescription) -> Estimability:
    """What trials of ``items`` can and cannot estimate on the described robot
    (:func:`odohil.science.path_estimability.plan_estimability` at its ``[priors]``,
    with its floor marks), as the session will estimate them: a plan naming a
    path is estimated from general paths, with the turn errors unless the
    robot's turns are exact (odohil/session/results/outcome.py ``estimate_paths``), a
    plan of forth-and-back designs with the four parameters; ``turn`` designs
    on a robot whose turns carry error then fold the turn errors into E_R and
    K_theta, and the statement says so (:data:`FOLDED_TURNS`).

    Raises:
        ParameterError: an empty plan, or priors at which the information is
            not defined (K_theta = 0 with exact poses).
    """
    robot = RobotModel.of(description)
    turns = any(
        any(step != 0.0 for step in shape_path(shape).turns.total_abs_rad) for shape, _ in items
    )
    if designs_only(items) and turns and not robot.turns_exact:
        four = plan_estimability(items, replace(robot, turns_exact=True))
        idle = acting([shape_path(shape) for shape, _ in items], robot)
        folded = "not fitted by the forth-and-back estimator (folded into E_R and K_theta)"
        return replace(
            four,
            turns_exact=False,
            not_estimable=tuple(
                (name, idle.get(name, folded)) for name in robot.names if name not in four.estimable
            ),
            notes=(*four.notes, FOLDED_TURNS),
        )
    statement = plan_estimability(items, robot)
    if robot.turns_exact and turns:
        exact = "Turns declared exact ([robot] turns_exact): no turn errors in the model"
        return replace(statement, notes=(*statement.notes, exact))
    return statement


def check_estimable(plan: Plan, description: RobotDescription) -> Estimability | None:
    """Refuse a plan whose trials, all driven, could give no estimate, and say
    what they can and cannot estimate (:func:`estimability`; None when the
    information is not defined at the priors). A plan of forth-and-back
    designs is held to the estimator's own rule
    (:func:`odohil.science.estimators.checks.plan_problems`, at the
    description's ``[priors]``); a plan naming a path to the statement's
    problems (one of the four or a turn error its trials make not identified,
    too few trials). ParameterError naming ``--plan``, the reason and what
    would make it estimable."""
    items = plan_items(plan)
    designs = [(shape, n) for shape, n in items if isinstance(shape, Design)]
    if len(designs) == len(items):
        problems = plan_problems(designs, description.priors.mean)
        if problems:
            raise ParameterError(
                f"--plan {plan.to_text()}: no estimate could come of these trials (nothing "
                "was driven): " + "; ".join(problems)
            )
    try:
        statement = estimability(items, description)
    except ParameterError:
        if len(designs) == len(items):
            return None
        raise
    if len(designs) < len(items) and not statement.ok:
        named = "; ".join(f"{shape_label(shape)} n={n}" for shape, n in items)
        raise ParameterError(
            f"--plan ({named}): no estimate could come of these trials (nothing "
            f"was driven): {'; '.join(statement.problems)}. What they would give: "
            + statement.text(problems=False)
        )
    return statement


def check_trials_per_design(
    plan: Plan,
    allow_few: bool,
    min_trials_per_design: int = DEFAULT_MIN_TRIALS_PER_DESIGN,
) -> None:
    """Refuse a plan with a design of fewer trials than the planner's minimum
    for honest intervals, unless ``allow_few`` (ParameterError naming
    ``--plan`` and ``--allow-few-trials``): such a session's estimate cannot
    be exported without ``--force`` (odohil/session/results/outcome.py)."""
    few = [
        f"{i.design.label()} (n={i.n_trials})"
        for i in plan.items
        if i.n_trials < min_trials_per_design
    ]
    if few and not allow_few:
        raise ParameterError(
            f"--plan has fewer than {units.plural(min_trials_per_design, 'trial')} a design "
            f"({', '.join(few)}), the planner's minimum for honest intervals: its estimate "
            "could not be exported. Give n >= "
            f"{min_trials_per_design} for every design, or --allow-few-trials to run it anyway"
        )
