"""``odohil demo --json``: a whole calibration of the fake robot, checked against its truth."""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import pytest

from odohil.science.parameters import PARAMETER_NAMES, SI_UNITS
from odohil.session.commands.demo import DEMO_PLAN, DEMO_TRUTH
from odohil.session.journal.state import load_session
from odohil.session.plans.plan import parse_plan

ODOHIL = shutil.which("odohil") or "odohil"


@pytest.mark.slow
def test_demo_estimates_contain_the_true_values(tmp_path: Path) -> None:
    done = subprocess.run(
        [ODOHIL, "demo", "--json", "--session", str(tmp_path / "s")],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 0, done.stderr
    assert "verdict: TRUSTED" in done.stderr  # every command that estimates says it (issue 18)
    result = json.loads(done.stdout)
    n_trials = parse_plan(DEMO_PLAN).n_trials
    assert result["n_trials"] == n_trials
    truth = DEMO_TRUTH.to_si_dict()
    assert result["truth"] == {
        name: {"value": truth[name], "unit": SI_UNITS[name]} for name in PARAMETER_NAMES
    }
    # The fake's true pose depends only on its seed (not on how the wall clock
    # slices the motion), so the demo a user runs with the default seed is
    # this very run: its 95 % intervals must contain the true values. Over
    # many seeds all four intervals together hold in about 80-85 % of runs
    # (BENCHMARKS.md); the default seed is one of those, and stays one.
    for name in PARAMETER_NAMES:
        entry = result["parameters"][name]
        low, high = entry["ci95"]
        assert low < truth[name] < high, (name, entry)
    state = load_session(tmp_path / "s").state
    assert state.finished
    assert sorted(t.trial for t in state.completed) == list(range(1, n_trials + 1))
