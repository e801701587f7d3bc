"""The comparison of general paths with forth-and-back plans as a planning
command would ask for it (odohil/session/commands/plan_paths.py, issue 19
deliverable 3): paths in the ``--path`` syntax, a time budget, the robot."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from odohil.errors import ParameterError
from odohil.robots import __file__ as robots_init
from odohil.session.commands.plan_paths import (
    PathComparisonRequest,
    compare_paths,
    comparison_document,
)

CREATE2 = Path(robots_init).parent / "create2.toml"


def test_squares_both_ways_buy_the_clockwise_turn_error_of_a_create2() -> None:
    found = compare_paths(
        PathComparisonRequest(
            "square:1,cw;square:1,ccw", 120.0, robot=CREATE2, split_directions=True
        )
    )
    assert "e_turn_spin_cw" in found.buys
    document: dict[str, Any] = json.loads(json.dumps(comparison_document(found), allow_nan=False))
    assert document["gains"]["e_turn_spin_cw"]["newly_estimable"] is True
    assert document["turn_free"]["parameters"]["e_turn_spin_cw"]["stderr_si"] is None
    reason = document["forth_and_back"]["parameters"]["e_turn_spin_cw"]["reason"]
    assert "makes no clockwise spins" in reason
    for plan in ("turn_free", "forth_and_back", "with_paths"):
        assert document[plan]["operator_minutes"] <= 120.0


def test_a_robot_whose_turns_are_exact_compares_the_four_only() -> None:
    found = compare_paths(PathComparisonRequest("square:2,cw;square:2,ccw", 120.0))
    assert [g.name for g in found.gains] == ["E_R", "E_T", "K_theta", "K_rho"]


@pytest.mark.parametrize(
    ("request_", "said"),
    [
        (PathComparisonRequest("", 60.0), "--compare-paths: give one or more paths"),
        (PathComparisonRequest("triangle:1", 60.0), "--compare-paths: 'triangle:1': unknown path"),
        (PathComparisonRequest("square:1", 0.0), "--budget-min must be a positive number"),
        (PathComparisonRequest("square:1", 60.0, sigma_m=-1.0), "--sigma-m must be a positive"),
    ],
)
def test_a_bad_request_names_the_option(request_: PathComparisonRequest, said: str) -> None:
    with pytest.raises(ParameterError, match=said.replace("(", r"\(")):
        compare_paths(request_)
