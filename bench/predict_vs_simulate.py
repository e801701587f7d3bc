"""Acceptance check at full size: ``odohil predict`` vs the mean of ``odohil simulate``.

Usage: ``python bench/predict_vs_simulate.py [--trials N] [--max-bias B]``

For k in {1, 3, 20} and both variants, with exaggerated errors (E_R = 20
deg/m, E_T = -0.05, K_theta = 200 deg^2/m, K_rho = 1e-3 m), runs the real
console commands and prints, for phi1..phi5, <x>, <y>, the z-score
(simulated - predicted) / Monte Carlo SE. phi2 is the sample variance of
dtheta, with the SE of a sample variance. The segment length of each case is
the coarsest of 2 mm, 1 mm, 0.5 mm, ... whose exact discretisation bias
(``discrete_means`` vs the closed forms) is at most ``--max-bias`` SE; the
SEs for that choice come from a 4,000-trial pilot run in-process.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np
import numpy.typing as npt

from odohil.science.parameters import ErrorParameters
from odohil.science.paths import Design, Variant
from odohil.science.simulator import discrete_means, simulate

ODOHIL = shutil.which("odohil") or "odohil"
PAPER = {"--E-R": "20", "--E-T": "-0.05", "--K-theta": "200", "--K-rho": "1e-3"}
PARAMS = ErrorParameters.from_paper_units(20.0, -0.05, 200.0, 1e-3)
CASES: list[tuple[float, float, Variant]] = [
    (1, 2.0, "turn"),
    (1, 2.0, "reverse"),
    (3, 1.0, "turn"),
    (3, 1.0, "reverse"),
    (20, 0.15, "turn"),
    (20, 0.15, "reverse"),
]
KEYS = ("phi1", "phi2", "phi3", "phi4", "phi5", "x", "y")


def odohil(*args: str) -> str:
    result = subprocess.run([ODOHIL, *args], capture_output=True, text=True, check=False)
    if result.returncode != 0:
        raise SystemExit(f"odohil {' '.join(args)} failed:\n{result.stderr}")
    return result.stdout


def statistics(pose: npt.NDArray[np.float64]) -> dict[str, tuple[float, float]]:
    """Each observable's estimate and Monte Carlo SE."""
    n = pose.shape[0]
    dx, dy, dtheta = pose[:, 0], pose[:, 1], pose[:, 2]

    def mean(v: npt.NDArray[np.float64]) -> tuple[float, float]:
        return float(v.mean()), float(v.std(ddof=1)) / math.sqrt(n)

    var = float(dtheta.var(ddof=1))
    m4 = float(np.mean((dtheta - dtheta.mean()) ** 4))
    var_se = math.sqrt((m4 - var**2 * (n - 3) / (n - 1)) / n)
    d2 = dx**2 + dy**2
    return {
        "phi1": mean(dtheta),
        "phi2": (var, var_se),
        "phi3": mean(dx),
        "phi4": mean(dy),
        "phi5": mean(d2),
        "x": mean(dx),
        "y": mean(dy),
    }


def bias_in_se(
    design: Design, predicted: dict[str, float], se: dict[str, float], seg: float
) -> float:
    exact = discrete_means(design.path(), PARAMS, seg)
    pairs = (("x", exact.x), ("y", exact.y), ("phi5", exact.square_distance))
    return max(abs(value - predicted[key]) / se[key] for key, value in pairs)


def choose_segment(
    design: Design, predicted: dict[str, float], n: int, max_bias: float
) -> tuple[float, float]:
    pilot = simulate(design.path(), PARAMS, 4000, seed=7, segment_m=0.002).pose_change
    se = {key: s * math.sqrt(4000 / n) for key, (_, s) in statistics(pilot).items()}
    seg = 0.002
    while (bias := bias_in_se(design, predicted, se, seg)) > max_bias:
        seg /= 2
    return seg, bias


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=200_000)
    parser.add_argument("--max-bias", type=float, default=1.0, help="in SE at --trials")
    args = parser.parse_args()
    flags = [item for pair in PAPER.items() for item in pair]
    print(f"{args.trials} trials per case; parameters {PAPER}; load {os.getloadavg()[0]:.2f}")
    header = f"{'design':>22} {'segment m':>10} {'bias/SE':>7} " + " ".join(f"{k:>6}" for k in KEYS)
    print(header + f" {'seconds':>8}")
    worst = 0.0
    with tempfile.TemporaryDirectory() as folder:
        for index, (k, l_m, variant) in enumerate(CASES):
            design = Design(k, l_m, variant)
            dargs = ["--k", str(k), "--l", str(l_m), "--variant", variant]
            predicted = json.loads(odohil("predict", *dargs, *flags, "--json"))
            seg, bias = choose_segment(design, predicted, args.trials, args.max_bias)
            out = Path(folder) / f"case{index}.csv"
            start = time.perf_counter()
            odohil(
                "simulate",
                *dargs,
                *flags,
                "--trials",
                str(args.trials),
                "--seed",
                str(2000 + index),
                "--segment-m",
                repr(seg),
                "--out",
                str(out),
            )
            elapsed = time.perf_counter() - start
            pose = np.loadtxt(out, delimiter=",", skiprows=1, usecols=(3, 4, 5))
            stats = statistics(pose)
            z = {key: (stats[key][0] - predicted[key]) / stats[key][1] for key in KEYS}
            worst = max(worst, *(abs(v) for v in z.values()))
            row = " ".join(f"{z[key]:6.2f}" for key in KEYS)
            print(f"{design.label():>22} {seg:10.3g} {bias:7.2f} {row} {elapsed:8.1f}")
    print(
        f"largest |z| = {worst:.2f} ({'PASS' if worst <= 4 else 'FAIL'} at 4 SE); "
        f"load {os.getloadavg()[0]:.2f}"
    )


if __name__ == "__main__":
    main()
