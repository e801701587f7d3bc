"""The --plan syntax."""

from __future__ import annotations

import pytest

from odohil.errors import ParameterError
from odohil.science.paths import Design
from odohil.session.plans.plan import Plan, PlanItem, parse_plan


def test_two_designs_with_and_without_variant() -> None:
    plan = parse_plan("k=1,l=6,n=30;k=20,l=0.5,n=30,variant=reverse")
    assert plan.items == (
        PlanItem(Design(1, 6.0, "turn"), 30),
        PlanItem(Design(20, 0.5, "reverse"), 30),
    )
    assert plan.n_trials == 60
    assert plan.distance_m == pytest.approx(30 * 12 + 30 * 20)


def test_trials_are_numbered_in_plan_order() -> None:
    plan = parse_plan("k=0.5,l=2,n=2; k=1,l=1,n=3")
    assert [plan.design_index(t) for t in range(1, 6)] == [0, 0, 1, 1, 1]
    with pytest.raises(ParameterError, match="outside"):
        plan.design_index(6)


def test_text_and_json_round_trip() -> None:
    plan = parse_plan("k=1.5,l=0.25,n=4,variant=turn;k=2,l=1,n=1,variant=reverse")
    assert parse_plan(plan.to_text()) == plan
    assert Plan.from_json(plan.to_json()) == plan


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("", "empty plan"),
        ("k=1,l=6", "design 1.*missing n"),
        ("k=1,l=6,n=30;;k=1,l=1,n=1", "design 2 is empty"),
        ("k=1,l=6,n=0", "positive number of trials"),
        ("k=1,l=6,n=2.5", "whole number"),
        ("k=0.3,l=6,n=3", "multiple of 1/2"),
        ("k=1,l=-1,n=3", "positive length"),
        ("k=1,l=1,n=3,variant=spin", "variant must be one of"),
        ("k=1,l=1,n=3,m=2", "unknown key 'm'"),
        ("k=1,k=2,l=1,n=3", "k is given twice"),
        ("k=1,l,n=3", "expected key=value"),
        ("k=one,l=1,n=3", "k must be a number"),
    ],
)
def test_bad_plans_are_rejected_with_a_reason(text: str, message: str) -> None:
    with pytest.raises(ParameterError, match=message):
        parse_plan(text)
