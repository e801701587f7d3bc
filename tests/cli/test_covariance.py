"""``odohil covariance``, run as the real console command."""

from __future__ import annotations

import json
import os
import shutil
import subprocess

import numpy as np
import pytest

from odohil.science.moments import pose_moments
from odohil.science.parameters import NOMAD150, ErrorParameters
from odohil.science.paths import Design, square
from tests import forked

ODOHIL = shutil.which("odohil") or "odohil"


def run(*args: str) -> subprocess.CompletedProcess[str]:
    # a process of its own, forked from a server that imported odohil once (tests/forked.py)
    env = {**os.environ, "COLUMNS": "160", "NO_COLOR": "1"}
    return forked.completed([ODOHIL, "covariance", *args], 120, env)


def test_forth_and_back_closed_form_json() -> None:
    result = run("--path", "forth-and-back", "--k", "1.5", "--l", "4", "--variant", "reverse",
                 "--K-theta", "0.02", "--json")  # fmt: skip
    assert result.returncode == 0, result.stderr
    document = json.loads(result.stdout)
    params = ErrorParameters.from_paper_units(-0.202, -0.02, 0.02, 3.6e-5)
    expected = pose_moments(Design(1.5, 4.0, "reverse").path(), params)
    np.testing.assert_allclose(document["closed_form"]["mean"], expected.mean, atol=1e-15)
    np.testing.assert_allclose(document["closed_form"]["cov"], expected.cov, rtol=1e-12)
    assert "simulated" not in document
    assert document["distance_m"] == pytest.approx(12.0)


def test_square_simulation_agrees_with_the_closed_form() -> None:
    result = run("--path", "square", "--side", "2", "--K-rho", "1e-4", "--simulate", "3000",
                 "--seed", "5", "--segment-m", "0.004", "--json")  # fmt: skip
    assert result.returncode == 0, result.stderr
    document = json.loads(result.stdout)
    sim = document["simulated"]
    assert sim["n_trials"] == 3000
    params = ErrorParameters(NOMAD150.e_r, NOMAD150.e_t, NOMAD150.k_theta, 1e-4)
    exact = pose_moments(square(2.0), params)
    assert np.all(np.abs(np.array(sim["mean"]) - exact.mean) <= 4 * np.array(sim["mean_se"]))
    assert np.all(np.abs(np.array(sim["cov"]) - exact.cov) <= 4 * np.array(sim["cov_se"]))


def test_table_output() -> None:
    result = run("--path", "square", "--side", "3", "--simulate", "200", "--seed", "1",
                 "--segment-m", "0.01")  # fmt: skip
    assert result.returncode == 0, result.stderr
    assert "closed form" in result.stdout
    assert "simulated (200 trials)" in result.stdout
    assert "cov(x, Delta)" in result.stdout


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (("--path", "square"), "needs --side"),
        (("--path", "square", "--side", "2", "--k", "1"), "forth-and-back"),
        (("--path", "forth-and-back", "--k", "1"), "needs --k and --l"),
        (("--path", "forth-and-back", "--k", "0.3", "--l", "2"), "multiple of 1/2"),
        (("--path", "square", "--side", "-1"), "side"),
        (("--path", "square", "--side", "1", "--simulate", "1"), "at least 2"),
        (("--path", "square", "--side", "1", "--K-rho", "-1"), "K-rho"),
        (("--path", "circle"), "circle"),
    ],
)
def test_bad_input_exits_2_with_a_clear_message(args: tuple[str, ...], message: str) -> None:
    result = run(*args)
    assert result.returncode == 2
    assert message in result.stderr.replace("\n", " ").replace("│", " ")
