"""The plan of a session and what it must satisfy before anything moves.

- plan.py: :class:`Plan` (designs and general paths, each n times), ``parse_plan``,
  ``check_session_plan``;
- checks.py: the plan against the robot: turns, estimability, trials per
  design, free floor.
"""

from odohil.session.plans.checks import (
    check_estimable,
    check_floor,
    check_trials_per_design,
    check_turns,
    default_variant,
    estimability,
    plan_items,
    turn_designs,
    turn_warning,
)
from odohil.session.plans.plan import (
    Plan,
    PlanItem,
    TrialShape,
    check_session_plan,
    driven_backward,
    parse_plan,
)

__all__ = [
    "Plan",
    "PlanItem",
    "TrialShape",
    "check_estimable",
    "check_floor",
    "check_session_plan",
    "check_trials_per_design",
    "check_turns",
    "default_variant",
    "driven_backward",
    "estimability",
    "parse_plan",
    "plan_items",
    "turn_designs",
    "turn_warning",
]
