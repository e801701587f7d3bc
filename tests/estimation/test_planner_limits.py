"""The planner's minimum trials per design, complete targets, evaluation and time model."""

from __future__ import annotations

import math

import numpy as np
import pytest

from odohil.driver.nomad.motion import DEFAULT_SPEEDS
from odohil.errors import ParameterError
from odohil.science.exports import Linearisation
from odohil.science.fisher import default_description
from odohil.science.parameters import NOMAD150
from odohil.science.paths import Design
from odohil.science.planner import (
    OperatorTime,
    evaluate_plan,
    expected_standard_errors,
    plan_experiment,
)
from odohil.science.targets import default_targets

ONE_MM = default_description(0.001)
DESIGNS = [Design(1, 2.0), Design(1, 6.0), Design(0.5, 4.0), Design(5, 1.0)]


def test_every_design_of_a_plan_has_the_minimum_trials() -> None:
    for minimum in (10, 17):
        plan = plan_experiment(
            NOMAD150, 400.0, description=ONE_MM, designs=DESIGNS, min_trials_per_design=minimum
        )
        assert all(item.n_trials >= minimum for item in plan.items)
        assert plan.honest
        assert plan.distance_m <= 400.0
    with pytest.raises(ParameterError, match="no candidate design fits 10 trials"):
        plan_experiment(NOMAD150, 100.0, designs=[Design(1, 6.0)])  # 10 x 12 m > 100 m


def test_targets_not_given_default_to_fractions_of_the_prior() -> None:
    plan = plan_experiment(
        NOMAD150, 300.0, description=ONE_MM, designs=DESIGNS, targets={"E_R": math.radians(1e-2)}
    )
    assert plan.targets == {**default_targets(NOMAD150), "E_R": math.radians(1e-2)}
    ratios = plan.standard_errors / np.array([plan.targets[n] for n in plan.targets])
    assert plan.criterion == pytest.approx(ratios.max())
    assert plan.meets_targets == bool(ratios.max() <= 1)


def test_evaluate_scores_the_plan_as_written() -> None:
    written = [(Design(1, 6.0), 30), (Design(20, 0.5), 4)]
    plan = evaluate_plan(written, NOMAD150, description=ONE_MM)
    np.testing.assert_allclose(
        plan.standard_errors, expected_standard_errors(written, NOMAD150, ONE_MM)
    )
    assert not plan.honest
    assert len(plan.notes) == 1
    assert "k=20 l=0.5 m turn: 4 trials" in plan.notes[0]


def test_the_time_model_and_a_time_budget() -> None:
    assert (OperatorTime().speed_m_per_s, OperatorTime().turn_rate_rad_per_s) == DEFAULT_SPEEDS
    assert Linearisation().speed_m_per_s == DEFAULT_SPEEDS[0]  # the exports' default speed
    model = OperatorTime(100.0, 0.5, math.pi / 2)
    # k=1: out, half turn, back, half turn: 12 m and two half turns of 2 s
    assert model.trial_seconds(Design(1, 6.0)) == pytest.approx(100 + 24 + 4)
    assert model.trial_seconds(Design(1, 6.0, "reverse")) == pytest.approx(100 + 24)
    plan = plan_experiment(
        NOMAD150, math.inf, description=ONE_MM, designs=DESIGNS, operator=model, budget_s=3000.0
    )
    assert plan.duration_s <= 3000.0
    assert plan.n_trials >= 10
