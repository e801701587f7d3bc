"""Does a session's plan fit the free floor of the robot description?

The robot drives along one line; one-way trials alternate direction
(:func:`odohil.science.paths.floor_choreography`), so a plan needs as much
free floor as the span its trials cover (:attr:`Plan.excursion_m`). With
``[floor] length_m`` in the robot description, a plan that needs more is
refused before anything moves. A general path (a square, a polygon, a
circle) is closed: it starts and ends on its start mark, so it adds nothing to
the line's span; its floor need is its bounding box around the start mark
(:func:`~odohil.session.plans.plan.path_floor_m`), whose longer side must fit the
given length too.
"""

from __future__ import annotations

from odohil.errors import ParameterError
from odohil.science.path_designs import PathDesign
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
