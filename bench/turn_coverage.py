"""Benchmark: coverage of the general-path fit with a differential drive's turn errors.

Usage: ``python bench/turn_coverage.py [--replications 1000] [--workers 2]
[--method robust] [--seed S]``

Each replication is one simulated data set of general paths with a known
turn-scale error (issue 20, acceptance: the fit with e_turn covers the truth
93-97 % for every parameter): 6 counter-clockwise and 6 clockwise 0.75 m
squares turning in place (spins), 6 and 6 circles of radius 0.3 m, two laps,
cut into 24 legs and arc turns, and 4 straight runs of 1.5 m, each trial on
the discrete model with turn errors (odohil/science/diff_drive.py
simulate_turn_errors, 5 mm segments) plus motion-capture noise (0.3 mm on x
and y, 0.05 degree on the heading). Truth: E_R -0.5 deg/m, E_T -0.3 %,
K_theta 0.2 deg^2/m, K_rho 2e-5 m, e_turn -0.7 % on spins and -1.2 % on arcs,
K_spin 1e-4 rad^2/rad (close to the optiodom robot, K_rho raised so that it
is identified). Fitted by odohil/science/estimators/paths.py estimate_paths
with turns_exact=False and the default split rule (e_turn per kind, per
direction when the likelihood-ratio test asks for it). Reports per parameter
the 95 % interval coverage with its Monte Carlo SE, the mean estimate, the
4-sigma misses and the verdicts.
"""

from __future__ import annotations

import argparse
import math
import multiprocessing
import os
import time

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

from dataclasses import dataclass  # noqa: E402

import numpy as np  # noqa: E402

from odohil.science.diff_drive import simulate_turn_errors  # noqa: E402
from odohil.science.estimators.paths import estimate_paths  # noqa: E402
from odohil.science.moments import TurnErrors  # noqa: E402
from odohil.science.parameters import ErrorParameters  # noqa: E402
from odohil.science.path_trials import PathTrial  # noqa: E402
from odohil.science.paths import TURN_CLASSES, EncoderPath, Leg, Step, Turn  # noqa: E402

TRUTH = ErrorParameters.from_paper_units(-0.5, -0.003, 0.2, 2e-5)
TURNS = TurnErrors(-0.007, -0.007, -0.012, -0.012, k_spin=1e-4)
MEASUREMENT = np.diag([0.3e-3**2, 0.3e-3**2, math.radians(0.05) ** 2])
SEGMENT_M = 0.005


def square(ccw: bool) -> EncoderPath:
    """A 0.75 m square turning 90 degrees in place at each corner."""
    angle = math.pi / 2 * (1 if ccw else -1)
    steps: list[Step] = []
    for _ in range(4):
        steps += [Leg(0.75), Turn(angle, "spin")]
    return EncoderPath(tuple(steps), name=f"square {'ccw' if ccw else 'cw'}")


def circle(ccw: bool, radius_m: float = 0.3, laps: float = 2.0, legs: int = 24) -> EncoderPath:
    """A circle cut into ``legs`` chords, its heading changes as arc turns."""
    angle = 2 * math.pi * laps / legs * (1 if ccw else -1)
    chord = 2 * radius_m * math.sin(abs(angle) / 2)
    steps: list[Step] = [Turn(angle / 2, "arc")]
    for i in range(legs):
        steps += [Leg(chord), Turn(angle if i < legs - 1 else angle / 2, "arc")]
    return EncoderPath(tuple(steps), name=f"circle {'ccw' if ccw else 'cw'}")


PLAN: tuple[tuple[EncoderPath, str, str, int], ...] = (
    (square(True), "square", "ccw", 6),
    (square(False), "square", "cw", 6),
    (circle(True), "circle", "ccw", 6),
    (circle(False), "circle", "cw", 6),
    (EncoderPath((Leg(1.5),), name="straight"), "straight", "forward", 4),
)


def data_set(rng: np.random.Generator) -> list[PathTrial]:
    """One simulated data set (module docstring)."""
    trials: list[PathTrial] = []
    for path, family, direction, n in PLAN:
        poses = simulate_turn_errors(path, TRUTH, TURNS, n, seed=rng, segment_m=SEGMENT_M)
        for pose in poses.pose_change:
            noisy = pose + rng.multivariate_normal(np.zeros(3), MEASUREMENT)
            trials.append(
                PathTrial(
                    path,
                    noisy,
                    MEASUREMENT,
                    trial=len(trials) + 1,
                    family=family,
                    direction=direction,  # type: ignore[arg-type]
                )
            )
    return trials


def truth_of(name: str) -> float:
    """The true value (SI) of a fitted parameter, turn errors by their classes."""
    four = dict(zip(("E_R", "E_T", "K_theta", "K_rho"), TRUTH.as_tuple(), strict=True))
    if name in four:
        return four[name]
    if name == "K_spin":
        return TURNS.k_spin
    parts = name.split("_")[2:]
    rows = [r for r, label in enumerate(TURN_CLASSES) if all(p in label.split() for p in parts)]
    values = {float(TURNS.scales[r]) for r in rows}
    assert len(values) == 1, name
    return values.pop()


@dataclass(frozen=True)
class Outcome:
    """One replication: per parameter kind (see :func:`kind`), covered at 95 %,
    outside 4 sigma, estimate; the verdict; the split note."""

    covered: dict[str, bool]
    outside: dict[str, bool]
    values: dict[str, float]
    verdict: str
    split: bool
    seconds: float
    failure: str = ""
    reasons: tuple[str, ...] = ()


def kind(name: str) -> str:
    """Report spin and arc turn scales apart whatever the split."""
    if name.startswith("e_turn"):
        return "e_turn_spin" if "spin" in name else "e_turn_arc"
    return name


def replicate(seed: int, method: str) -> Outcome:
    """Simulate and fit one data set."""
    rng = np.random.default_rng(seed)
    trials = data_set(rng)
    start = time.process_time()
    try:
        result = estimate_paths(trials, turns_exact=False, method=method)
    except Exception as error:  # a benchmark records every failure
        return Outcome({}, {}, {}, "error", False, 0.0, f"{type(error).__name__}: {error}")
    seconds = time.process_time() - start
    covered: dict[str, bool] = {}
    outside: dict[str, bool] = {}
    values: dict[str, float] = {}
    for p in result.parameters:
        truth = truth_of(p.name)
        key = kind(p.name)
        covered[key] = covered.get(key, True) and p.contains(truth, "95")
        outside[key] = outside.get(key, False) or not p.contains(truth)
        values[key] = p.value
    split = any("split by direction" in note for note in result.notes)
    reasons = tuple(f"seed {seed}: {r}" for r in result.verdict.reasons)
    return Outcome(covered, outside, values, result.verdict.status, split, seconds, "", reasons)


def _run(job: tuple[int, str]) -> Outcome:
    return replicate(*job)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--replications", type=int, default=1000)
    parser.add_argument("--workers", type=int, default=1)
    parser.add_argument("--method", default="robust")
    parser.add_argument("--seed", type=int, default=20261125)
    parser.add_argument("--report-every", type=int, default=100)
    args = parser.parse_args()
    print(f"load average before: {os.getloadavg()[0]:.2f}; {args.workers} workers", flush=True)
    jobs = [(args.seed + i, args.method) for i in range(args.replications)]
    started = time.time()
    outcomes: list[Outcome] = []
    with multiprocessing.Pool(args.workers) as pool:
        for outcome in pool.imap(_run, jobs, chunksize=2):
            outcomes.append(outcome)
            if len(outcomes) % args.report_every == 0 and len(outcomes) < len(jobs):
                report(outcomes, args.method, time.time() - started)
    report(outcomes, args.method, time.time() - started)


def report(outcomes: list[Outcome], method: str, wall: float) -> None:
    """Print the coverage table of the replications so far."""
    done = [o for o in outcomes if not o.failure]
    failures = [o.failure for o in outcomes if o.failure]
    print(
        f"{len(done)} of {len(outcomes)} data sets fitted ({method}), wall {wall:.0f} s, "
        f"median CPU per fit {np.median([o.seconds for o in done]):.2f} s; "
        f"load average now: {os.getloadavg()[0]:.2f}"
    )
    verdicts: dict[str, int] = {}
    for o in done:
        verdicts[o.verdict] = verdicts.get(o.verdict, 0) + 1
    print(f"verdicts: {verdicts}; e_turn split by direction in {sum(o.split for o in done)}")
    print("| parameter | truth | mean estimate | 95 % coverage | MC SE | outside 4-sigma |")
    print("|---|---|---|---|---|---|")
    for name in ("E_R", "E_T", "K_theta", "K_rho", "e_turn_spin", "e_turn_arc", "K_spin"):
        hits = [o.covered[name] for o in done if name in o.covered]
        if not hits:
            continue
        rate = float(np.mean(hits))
        se = math.sqrt(rate * (1 - rate) / len(hits))
        mean = float(np.mean([o.values[name] for o in done if name in o.values]))
        misses = sum(o.outside[name] for o in done if name in o.outside)
        print(f"| {name} | {truth_of(name):.4g} | {mean:.4g} | {rate:.3f} | {se:.3f} | {misses} |")
    for failure in failures[:10]:
        print("failure:", failure)
    for reason in [r for o in done for r in o.reasons][:10]:
        print("not trusted:", reason)
    print(flush=True)


if __name__ == "__main__":
    main()
