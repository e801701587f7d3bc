"""Does a session's plan fit the free floor of the robot description?

The robot drives along one line; one-way trials alternate direction
(:func:`odohil.science.paths.floor_choreography`), so a plan needs as much
free floor as the span its trials cover (:attr:`Plan.excursion_m`). With
``[floor] length_m`` in the robot description, a plan that needs more is
refused before anything moves.
"""

from __future__ import annotations

from odohil.errors import ParameterError
from odohil.science.paths import floor_choreography
from odohil.science.robot_description import RobotDescription
from odohil.session.plan import Plan

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
    pairs = [(item.design, item.n_trials) for item in plan.items]
    for number in range(1, len(pairs) + 1):
        needed = floor_choreography(pairs[:number], alternate=plan.alternate).excursion_m
        if needed > floor + FLOOR_SLACK_M:
            design = plan.items[number - 1].design
            raise ParameterError(
                f"plan design {number} ({design.label()}) takes the robot over {needed:g} m "
                f"of floor, but the robot description's [floor] length_m is {floor:g} m: "
                "shorten l (or the designs before it) or give a longer floor"
            )
    raise AssertionError("unreachable")
