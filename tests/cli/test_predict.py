"""``odohil predict``, run as the real console command."""

from __future__ import annotations

import json
import math
import os
import shutil
import subprocess

import pytest

from odohil.science.closed_forms import forth_and_back_means
from odohil.science.parameters import NOMAD150, ErrorParameters
from odohil.science.paths import Design
from tests import forked

ODOHIL = shutil.which("odohil") or "odohil"


def run(*args: str) -> subprocess.CompletedProcess[str]:
    # a process of its own, forked from a server that imported odohil once (tests/forked.py)
    env = {**os.environ, "COLUMNS": "160", "NO_COLOR": "1"}
    return forked.completed([ODOHIL, "predict", *args], 60, env)


def test_json_defaults_are_the_nomad150_closed_forms() -> None:
    result = run("--k", "20", "--l", "0.5", "--json")
    assert result.returncode == 0, result.stderr
    document = json.loads(result.stdout)
    expected = forth_and_back_means(Design(20, 0.5, "turn"), NOMAD150)
    for key, value in expected.as_dict().items():
        assert document[key] == pytest.approx(value, rel=1e-12, abs=1e-300)
    assert document["design"] == {"k": 20, "l_m": 0.5, "variant": "turn"}
    assert document["parameters"]["E_R"] == pytest.approx(math.radians(-0.202))
    assert document["parameters"]["E_T"] == pytest.approx(-0.02)
    assert document["units"]["phi2"] == "rad^2"
    assert document["units"]["phi5"] == "m^2"


def test_json_takes_parameters_in_paper_units() -> None:
    result = run(
        "--k", "1.5", "--l", "2", "--variant", "reverse",
        "--E-R", "12", "--E-T", "0.05", "--K-theta", "150", "--K-rho", "1e-3", "--json",
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    document = json.loads(result.stdout)
    params = ErrorParameters(
        e_r=12 * math.pi / 180, e_t=0.05, k_theta=150 * (math.pi / 180) ** 2, k_rho=1e-3
    )
    expected = forth_and_back_means(Design(1.5, 2.0, "reverse"), params)
    for key, value in expected.as_dict().items():
        assert document[key] == pytest.approx(value, rel=1e-12), key
    assert document["parameters"]["K_theta"] == pytest.approx(params.k_theta, rel=1e-15)


def test_table_names_every_unit_and_shows_degrees() -> None:
    result = run("--k", "1", "--l", "6")
    assert result.returncode == 0, result.stderr
    out = result.stdout
    means = forth_and_back_means(Design(1, 6.0, "turn"), NOMAD150)
    for name in ("phi1", "phi2", "phi3", "phi4", "phi5", "rad^2", "m^2", "deg^2", "deg/m"):
        assert name in out
    assert f"{means.phi1:.6g}" in out
    assert f"{math.degrees(means.phi1):.6g} deg" in out
    assert f"{means.phi2 * (180 / math.pi) ** 2:.6g} deg^2" in out
    assert f"{means.y:.6g}" in out


@pytest.mark.parametrize(
    "args",
    [
        ("--k", "0.3", "--l", "1"),
        ("--k", "1", "--l", "-2"),
        ("--k", "1", "--l", "1", "--K-theta", "-0.1"),
        ("--k", "1", "--l", "1", "--K-rho", "-1e-5"),
        ("--k", "1", "--l", "1", "--E-T", "-1"),
        ("--k", "1", "--l", "1", "--variant", "sideways"),
        ("--k", "one", "--l", "1"),
    ],
)
def test_bad_input_exits_2_without_traceback(args: tuple[str, ...]) -> None:
    result = run(*args)
    assert result.returncode == 2
    assert "Traceback" not in result.stderr + result.stdout
    assert "Error" in result.stderr
