"""A fit that creeps to its root must not be called unconverged.

tests/estimation/data/create2_turns_seed12.jsonl is the session CI's run of
tests/cli/test_turn_scale_paths.py gave at stop 35 (the same plan on
``fakecreate2://?seed=12&...&turn_scale=0.02``, written with
``write_path_trials``): K_theta's root lies near 0 (about 1e-7 deg^2/m), where
its information vanishes and Fisher scoring halves the remaining step every
two iterations. The first refine ended at 60 steps within 1e-4 standard errors
of the root; the rescue from L-BFGS-B converged to the same point, and the
two were compared by their NLL, which the unconverged one won by 3e-12: the
verdict was FAILED, "the fit did not converge", where the fit had.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from odohil.session.results.outcome import estimate_source
from odohil.session.robots.description import load_robot_description, resolve_robot

SESSION = Path(__file__).parent / "data" / "create2_turns_seed12.jsonl"


@pytest.mark.parametrize("method", ["joint", "robust"])
def test_a_fit_that_creeps_to_its_root_converges(method: str) -> None:
    create2 = load_robot_description(resolve_robot("create2"))
    outcome = estimate_source([SESSION], create2, method=method)
    result, verdict = outcome.result, outcome.verdict
    assert result is not None
    assert verdict is not None
    assert result.converged, result.notes
    # doubtful for its few trials a path family (6 each), nothing else
    assert verdict.status == "doubtful", verdict.reasons
    assert len(verdict.reasons) == 1, verdict.reasons
    assert "fewer than 10 trials a path family" in verdict.reasons[0]
