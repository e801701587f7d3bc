"""An export refusal gives the interval and the value in the units the estimate
is printed in (E_R in deg/m beside "E_R -0.2123 deg/m"), not in SI without a
unit ("E_R's 95 % interval [-0.006797, -0.0006151]": found on a three-trial run)."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest
from typer.testing import CliRunner

from odohil import units
from odohil.cli.app import app
from odohil.cli.exit_codes import EXIT_UNTRUSTED


def test_a_correction_refusal_names_its_unit(tmp_path: Path) -> None:
    session = tmp_path / "s"
    done = CliRunner().invoke(
        app,
        ["run", "--robot", "nomad150", "--port", "fakerobot://?seed=3&time_scale=2000",
         "--plan", "k=1,l=1,n=3", "--measure", "fake", "--allow-few-trials",
         "--session", str(session), "--json"],
    )  # fmt: skip
    assert done.exit_code == EXIT_UNTRUSTED, done.output  # 3 trials: below the minimum
    said = " ".join(done.stderr.split())
    found = re.search(
        r"E_R's 95 % interval \[(\S+), (\S+)\] deg/m is wider than its value (\S+) deg/m", said
    )
    assert found is not None, said
    shown = [float(v) for v in found.groups()]
    e_r = json.loads(done.stdout)["parameters"]["E_R"]  # SI, rad/m
    si = [*e_r["ci95"], e_r["value"]]
    assert shown == pytest.approx([units.rad_per_m_to_deg_per_m(v) for v in si], rel=1e-3)
