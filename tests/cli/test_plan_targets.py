"""``odohil plan``: targets for all four parameters, honest claims, a minimum
number of trials per design, ``--evaluate``, and operator time."""

from __future__ import annotations

import json
import os
import shutil
import subprocess

from odohil.science.parameters import NOMAD150, PARAMETER_NAMES

ODOHIL = shutil.which("odohil") or "odohil"


def run(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [ODOHIL, "plan", *args],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
        env={**os.environ, "COLUMNS": "160", "NO_COLOR": "1"},
    )


def test_a_target_on_e_r_alone_does_not_claim_targets_it_misses() -> None:
    """Issue 11: ``--budget-m 300 --target-E-R 0.01`` recommended 2 trials and
    said "The plan meets every target" while the standard errors of E_T
    (0.0199) and K_rho (3.64e-5) equalled their priors."""
    result = run("--budget-m", "300", "--target-E-R", "0.01", "--json")
    assert result.returncode == 0, result.stderr
    document = json.loads(result.stdout)
    errors = document["expected_stderr"]
    prior = dict(zip(PARAMETER_NAMES, NOMAD150.as_tuple(), strict=True))
    for name in PARAMETER_NAMES:
        assert "target_si" in errors[name], name  # every parameter has a target
        # no target is as loose as the prior itself
        assert errors[name]["target_si"] < abs(prior[name])
    met = all(e["stderr_si"] <= e["target_si"] for e in errors.values())
    assert document["meets_targets"] is met
    table = run("--budget-m", "300", "--target-E-R", "0.01")
    assert table.returncode == 0, table.stderr
    if not met:
        assert "meets every target" not in table.stdout
        assert "does NOT meet" in table.stdout
