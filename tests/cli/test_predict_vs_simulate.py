"""Acceptance check: ``odohil predict`` agrees with the mean of ``odohil simulate``.

Both run as the real console commands, with exaggerated errors, for k in
{1, 3, 20} and both variants. The simulation uses 20,000 trials at a segment
length whose discretisation bias (exact, from :func:`discrete_means`) is at
most half a standard error, so the comparison is with the N -> infinity
closed forms at 4 Monte Carlo standard errors. ``bench/predict_vs_simulate.py``
runs the same check with 200,000 trials.
"""

from __future__ import annotations

import json
import math
import os
import shutil
from pathlib import Path

import numpy as np
import numpy.typing as npt
import pytest

from odohil.science.parameters import ErrorParameters
from odohil.science.paths import Design, Variant
from odohil.science.simulator import discrete_means
from tests import forked

ODOHIL = shutil.which("odohil") or "odohil"
ENV = {**os.environ, "COLUMNS": "160", "NO_COLOR": "1"}
Z = 4.0
N_TRIALS = 20_000
PAPER = {"--E-R": "20", "--E-T": "-0.05", "--K-theta": "200", "--K-rho": "1e-3"}
PARAMS = ErrorParameters.from_paper_units(20.0, -0.05, 200.0, 1e-3)
CASES: list[tuple[float, float, Variant, float]] = [  # k, l (m), variant, segment (m)
    (1, 2.0, "turn", 0.005),
    (1, 2.0, "reverse", 0.002),
    (3, 1.0, "turn", 0.005),
    (3, 1.0, "reverse", 0.001),
    (20, 0.15, "turn", 0.005),
    (20, 0.15, "reverse", 0.0002),
]
KEYS = ("phi1", "phi2", "phi3", "phi4", "phi5", "x", "y")


def odohil(*args: str) -> str:
    # a process of its own, forked from a server that imported odohil once (tests/forked.py)
    result = forked.completed([ODOHIL, *args], 300, ENV)
    assert result.returncode == 0, result.stderr
    return result.stdout


def design_args(k: float, l_m: float, variant: str) -> list[str]:
    return ["--k", str(k), "--l", str(l_m), "--variant", variant]


def sample_statistics(pose: npt.NDArray[np.float64]) -> dict[str, tuple[float, float]]:
    """Each observable's estimate from the trials and its Monte Carlo standard error."""
    n = pose.shape[0]
    dx, dy, dtheta = pose[:, 0], pose[:, 1], pose[:, 2]

    def mean(v: npt.NDArray[np.float64]) -> tuple[float, float]:
        return float(v.mean()), float(v.std(ddof=1)) / math.sqrt(n)

    var = float(dtheta.var(ddof=1))
    m4 = float(np.mean((dtheta - dtheta.mean()) ** 4))
    # SE of a sample variance: sqrt((mu4 - sigma^4 (n - 3)/(n - 1)) / n)
    var_se = math.sqrt((m4 - var**2 * (n - 3) / (n - 1)) / n)
    return {
        "phi1": mean(dtheta),
        "phi2": (var, var_se),
        "phi3": mean(dx),
        "phi4": mean(dy),
        "phi5": mean(dx**2 + dy**2),
        "x": mean(dx),
        "y": mean(dy),
    }


@pytest.mark.parametrize(("k", "l_m", "variant", "segment_m"), CASES)
def test_predict_agrees_with_the_mean_of_simulate(
    tmp_path: Path, k: float, l_m: float, variant: Variant, segment_m: float
) -> None:
    flags = [item for pair in PAPER.items() for item in pair]
    predicted = json.loads(odohil("predict", *design_args(k, l_m, variant), *flags, "--json"))
    out = tmp_path / "trials.csv"
    odohil(
        "simulate",
        *design_args(k, l_m, variant),
        *flags,
        "--trials",
        str(N_TRIALS),
        "--seed",
        str(1000 + 10 * k + len(variant)),
        "--segment-m",
        str(segment_m),
        "--out",
        str(out),
    )
    pose = np.loadtxt(out, delimiter=",", skiprows=1, usecols=(3, 4, 5))
    assert pose.shape == (N_TRIALS, 3)
    stats = sample_statistics(pose)
    # the segment length is fine enough: its exact bias is under half an SE
    exact = discrete_means(Design(k, l_m, variant).path(), PARAMS, segment_m)
    for key, value in (("x", exact.x), ("y", exact.y), ("phi5", exact.square_distance)):
        assert abs(value - predicted[key]) <= 0.5 * stats[key][1], f"{key}: segment too coarse"
    failures = []
    for key in KEYS:
        estimate, se = stats[key]
        z = (estimate - predicted[key]) / se
        if abs(z) > Z:
            failures.append(
                f"{key}: simulated {estimate:.6g} predicted {predicted[key]:.6g} z={z:.2f}"
            )
    assert not failures, failures
