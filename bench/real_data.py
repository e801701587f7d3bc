"""Benchmark: odohil on a real robot's recording (the optiodom June sessions, issue 20).

Usage: ``python bench/real_data.py [--data ../shared/data/optiodom-june]``
(or ``$ODOHIL_OPTIODOM``). Prints, for BENCHMARKS.md "Real data (optiodom
June)":

- the fits (odohil/science/estimators/paths.py estimate_paths, robust, read by
  odohil/session/trials/logs with docs/examples/optiodom.toml): straight runs with the
  four-parameter model; circles with the four-parameter model, with one e_turn
  and with e_turn per direction; squares likewise; in-place spins with e_turn
  and K_spin; each with its verdict and wall time;
- what the data say about the model: the heading variance's growth with the
  distance driven within the straight runs (linear against quadratic), the
  normality of the straight-run fit's normalised residuals (Shapiro-Wilk and
  the QQ correlation per axis), the distance scale E_T on circles against the
  straight runs', K_rho against a tape's variance, and the first run of each
  session and direction against the others;
- the machine's load (``uptime``).
"""

from __future__ import annotations

import argparse
import math
import os
import subprocess
import time
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from scipy import stats

from odohil import units
from odohil.science.estimators.paths import estimate_paths, predict
from odohil.science.estimators.result import EstimateResult
from odohil.science.path_trials import PathTrial
from odohil.science.paths import FloatArray
from odohil.session.robots.description import load_robot_description
from odohil.session.trials.logs import ImportOptions, read_recording
from odohil.session.trials.logs.optiodom import read_run

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_DATA = Path(os.environ.get("ODOHIL_OPTIODOM", ROOT.parent / "shared/data/optiodom-june"))


def _params(result: EstimateResult) -> str:
    parts = []
    for p in result.parameters:
        v = units.parameter_to_paper(p.name, p.value)
        low, high = (units.parameter_to_paper(p.name, x) for x in p.ci95)
        scale, unit = (100.0, " %") if p.name == "E_T" or p.name.startswith("e_turn") else (1, "")
        parts.append(f"{p.name} {scale * v:.4g}{unit} [{scale * low:.4g}, {scale * high:.4g}]")
    return "; ".join(parts)


def fit(label: str, trials: Sequence[PathTrial], **kwargs: object) -> EstimateResult:
    """Fit, print the parameters (paper units), verdict and wall time."""
    start = time.perf_counter()
    result = estimate_paths(trials, **kwargs)  # type: ignore[arg-type]
    seconds = time.perf_counter() - start
    reasons = "; ".join(result.verdict.reasons)
    print(f"{label} ({len(trials)} trials, {seconds:.2f} s): {result.verdict.status}")
    print(f"    {_params(result)}")
    print(f"    goodness of fit: {result.model_check.verdict}")
    if reasons:
        print(f"    reasons: {reasons[:400]}")
    return result


def heading_growth(runs: Sequence[Path], step_m: float = 0.05, windows: int = 24) -> None:
    """Within the straight runs: the variance of the heading error's increment
    over a window of L metres driven (every window of every run, L = 0.05 to
    1.2 m), fitted as a + b L and as a + c L^2 (least squares); and across the
    runs, the heading error's variance at each distance from the start."""
    curves = []
    for path in runs:
        rec = read_run(path)
        odo = rec.odometry
        dist = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(odo[:, :2], axis=0).T))])
        keep = np.concatenate([[True], np.diff(dist) > 1e-9])
        err = np.unwrap(rec.truth[:, 2]) - np.unwrap(odo[:, 2])
        grid = np.arange(0.0, dist[-1] - 1e-6, step_m)
        curves.append(np.interp(grid, dist[keep], err[keep]))
    lengths = np.arange(1, windows + 1) * step_m
    var = np.array(
        [
            np.var(np.concatenate([c[k:] - c[:-k] for c in curves if len(c) > k]), ddof=1)
            for k in range(1, windows + 1)
        ]
    ) * units.rad2_to_deg2(1.0)
    _fit_growth("increments within runs", lengths, var)
    ends = min(len(c) for c in curves)
    at = np.array([c[:ends] - c[0] for c in curves])
    dist = np.arange(ends) * step_m
    spread = at.var(axis=0, ddof=1)[2:] * units.rad2_to_deg2(1.0)
    _fit_growth("across runs from the start", dist[2:], spread)


def _fit_growth(what: str, lengths: FloatArray, var: FloatArray) -> None:
    lin = np.polyfit(lengths, var, 1)
    lin_rss = float(np.sum((np.polyval(lin, lengths) - var) ** 2))
    design = np.column_stack([np.ones_like(lengths), lengths**2])
    quad, *_ = np.linalg.lstsq(design, var, rcond=None)
    quad_rss = float(np.sum((design @ quad - var) ** 2))
    print(
        f"heading variance, {what} (L {lengths[0]:.2f}-{lengths[-1]:.2f} m): linear "
        f"{lin[1]:.3g} deg^2 + {lin[0]:.3g} deg^2/m x L (residual SS {lin_rss:.2g}); quadratic "
        f"{quad[0]:.3g} deg^2 + {quad[1]:.3g} deg^2/m^2 x L^2 (residual SS {quad_rss:.2g})"
    )


def normality(trials: Sequence[PathTrial], result: EstimateResult) -> None:
    """Shapiro-Wilk and QQ correlation of each axis's normalised residuals."""
    z = []
    for p in predict(trials, result):
        z.append(p.residual / np.sqrt(np.diag(p.cov)))
    zs = np.array(z)
    for axis, name in enumerate(("x", "y", "theta")):
        w, p_value = stats.shapiro(zs[:, axis])
        (_, _), (_, _, r) = stats.probplot(zs[:, axis])
        print(
            f"    {name}: mean {zs[:, axis].mean():+.2f}, SD {zs[:, axis].std(ddof=1):.2f}, "
            f"Shapiro-Wilk W = {w:.3f} (p = {p_value:.2f}), QQ correlation {r:.3f}"
        )


def first_runs(trials: Sequence[PathTrial], result: EstimateResult) -> None:
    """The heading residual of each session and direction's first run against
    its other runs (clockwise runs mirrored onto the counter-clockwise frame:
    a first run that turns short does so both ways)."""
    groups: dict[tuple[str, str], list[tuple[str, float]]] = {}
    for trial, p in zip(trials, predict(trials, result), strict=True):
        key = (str(Path(trial.source).parent), trial.direction)
        sign = -1.0 if trial.direction in ("cw", "backward") else 1.0  # mirrored
        groups.setdefault(key, []).append((Path(trial.source).name, sign * float(p.residual[2])))
    diffs = []
    for members in groups.values():
        members.sort()
        if len(members) < 2:
            continue
        rest = np.mean([r for _, r in members[1:]])
        diffs.append(math.degrees(members[0][1] - rest))
    d = np.array(diffs)
    larger = int(np.sum(d > 0))
    print(
        f"first run minus the others' mean heading residual (cw mirrored), {len(d)} "
        "session-direction "
        f"groups: mean {d.mean():+.2f} deg (SE {d.std(ddof=1) / math.sqrt(len(d)):.2f}), "
        f"positive in {larger} of {len(d)}"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, default=DEFAULT_DATA)
    args = parser.parse_args()
    robot = load_robot_description(ROOT / "docs/examples/optiodom.toml")
    options = ImportOptions(format="optiodom")
    start = time.perf_counter()
    ivanjko = read_recording([args.data / "ivanjko"], robot, options)
    circles = read_recording([args.data / "circular"], robot, options)
    squares = read_recording([args.data / "square"], robot, options)
    print(f"read 102 runs in {time.perf_counter() - start:.2f} s (odohil/session/trials/logs)")
    straight = [t for t in ivanjko if t.family == "straight"]
    spins = [t for t in ivanjko if t.family == "spin"]
    print()
    print("## Fits (robust ML; paper units: deg/m, %, deg^2/m, m; e_turn %)")
    s4 = fit("straight runs, 4 parameters", straight, turns_exact=True)
    c4 = fit("circles, 4 parameters (turns exact)", circles, turns_exact=True)
    c1 = fit("circles, one e_turn", circles, turns_exact=False, split_directions=False)
    fit("circles, e_turn as the data ask (split by direction)", circles, turns_exact=False)
    fit("squares, 4 parameters (turns exact)", squares, turns_exact=True)
    fit("squares, e_turn as the data ask", squares, turns_exact=False)
    fit("spins, e_turn and K_spin", spins, turns_exact=False)
    fit("straight runs and spins, e_turn and K_spin", ivanjko, turns_exact=False)
    print()
    print("## What the data say about the model")
    heading_growth(sorted({Path(t.source) for t in straight}))
    print("normalised residuals of the straight-run fit (14 trials):")
    normality(straight, s4)
    print("normalised residuals of the circles' fit with one e_turn (32 trials):")
    normality(circles, c1)
    k_theta_ratio = c4.parameter("K_theta").value / s4.parameter("K_theta").value
    print(f"K_theta of the circles' 4-parameter fit / the straight runs': {k_theta_ratio:.0f}")
    e_t_s, e_t_c = s4.parameter("E_T"), c1.parameter("E_T")
    print(
        f"distance scale: E_T straight {100 * e_t_s.value:+.3f} % "
        f"(SE {100 * e_t_s.stderr:.3f}), circles {100 * e_t_c.value:+.3f} % "
        f"(SE {100 * e_t_c.stderr:.3f}); difference z = "
        f"{(e_t_c.value - e_t_s.value) / math.hypot(e_t_s.stderr, e_t_c.stderr):.1f}"
    )
    k_rho = s4.parameter("K_rho").value
    print(
        f"K_rho {k_rho:.2g} m: over a 2 m run K_rho x L = {k_rho * 2:.2g} m^2, "
        f"{k_rho * 2 / 1e-6:.2f} x the variance of one 1 mm tape reading"
    )
    print("circles (one e_turn):", end=" ")
    first_runs(circles, c1)
    sq = estimate_paths(squares, turns_exact=False)
    print("squares (e_turn as the data ask):", end=" ")
    first_runs(squares, sq)
    print()
    load = subprocess.run(["uptime"], capture_output=True, text=True, check=False).stdout.strip()
    print(f"uptime: {load}")


if __name__ == "__main__":
    main()
