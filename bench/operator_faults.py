"""Benchmark: is odohil ever confidently wrong when the operator slips?

Usage: ``python bench/operator_faults.py [--experiments 200] [--workers 2]
[--n-per-design 30] [--coverage-n 5,10,20,30] [--coverage-experiments 0] [--seed S]``

Simulated experiments through the full floor-marks path, the way a session
runs them (odohil/session/run/engine.py):

- the trials in the order and direction a session drives them (one-way
  trials alternate forwards and backwards, odohil/science/paths.py's
  floor_choreography); the true pose change of each from the discrete model
  (Nomad 150 values), its floor-mark distances from the forward model plus tape noise
  (Gaussian, or Student-t with 3 degrees of freedom scaled to the same SD),
  each distance mistyped at a given rate (+-1, +-2, +-5 or +-10 cm, or two
  adjacent digits of the millimetre reading transposed);
- the pose chosen by the one pose-selection path
  (odohil/science/pose_selection.py) against the encoders and the model's
  predictive distribution at the running estimate (the description's priors
  before there is one);
- the simulated operator reacts as the wizard asks: a set no rigid motion
  explains is measured again whole (three times at most, then the trial is
  lost); a slip-check alarm is answered by measuring the named distance again
  (twice at most; a trial still doubted is kept and flagged); an ambiguous
  trial is left out and listed;
- the final estimate by the default method, with its verdict.

Per configuration: the verdicts, the **confidently-wrong rate** (verdict
trusted, yet some parameter's truth outside the 4-sigma-equivalent interval
reported beside it, ``ci_4sigma``; counted beside it, the literal rule of more
than 4 printed Wald standard errors, and that rule on the log scale for
K_theta and K_rho), the 95 % coverage per parameter, and the trials re-measured, lost,
ambiguous. Clean configurations (no typos) give the **false-alarm rate**
(verdict not trusted on clean data). ``--coverage-experiments`` adds the
coverage and K_theta bias of the paper's designs at each ``--coverage-n``.
Every rate is printed with its binomial Monte Carlo standard error.
"""

from __future__ import annotations

import argparse
import contextlib
import itertools
import math
import multiprocessing
import os
import sys
import time

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

from collections.abc import Sequence  # noqa: E402
from dataclasses import dataclass, field  # noqa: E402

import numpy as np  # noqa: E402
from scipy import stats  # noqa: E402

from odohil.errors import InconsistentMeasurementError, OdohilError  # noqa: E402
from odohil.science.estimators import IncrementalEstimator, Observation, estimate  # noqa: E402
from odohil.science.fisher import default_description  # noqa: E402
from odohil.science.floor_marks import MarkDistances, marks_from_pose  # noqa: E402
from odohil.science.parameters import NOMAD150, PARAMETER_NAMES, ErrorParameters  # noqa: E402
from odohil.science.paths import Design, floor_choreography  # noqa: E402
from odohil.science.pose_selection import (  # noqa: E402
    ParameterBelief,
    predictive_pose,
    redundancy_problems,
    select_pose,
)
from odohil.science.robot_description import RobotDescription  # noqa: E402
from odohil.science.simulator import simulate  # noqa: E402
from odohil.units import wrap_angle  # noqa: E402

MAX_REJECTIONS = 3
MAX_REMEASURES = 2
TYPO_SHIFTS_M = (0.01, 0.02, 0.05, 0.10)
WRONG_SE = 4.0
SPURIOUS_D2 = float(stats.chi2.isf(2 * stats.norm.sf(WRONG_SE), 3))
"""A chosen pose farther than this (squared Mahalanobis distance, under its
own floor-mark covariance) from the true pose is spurious (4-sigma-equivalent)."""
TYPO_KEPT_M = 0.005
"""A kept trial with a reading this far from the exact distance carries a typo."""


def _pose_miss(chosen: np.ndarray, cov: np.ndarray, true: np.ndarray) -> float:
    delta = np.asarray(chosen, dtype=np.float64) - np.asarray(true, dtype=np.float64)
    delta[2] = wrap_angle(float(delta[2]))
    return float(delta @ np.linalg.pinv(cov) @ delta)


@dataclass(frozen=True)
class Config:
    """One experimental situation.

    Attributes:
        name: short label.
        designs: (k, l_m) of each design (``turn`` variant).
        n_cross: cross distances measured (1 or 2).
        noise: ``gauss`` or ``t3``.
        typo_rate: probability that one distance is mistyped.
    """

    name: str
    designs: tuple[tuple[float, float], ...]
    n_cross: int
    noise: str
    typo_rate: float


CLOSED = ((1.0, 6.0), (20.0, 0.5))
ONE_WAY = ((1.0, 2.0), (0.5, 2.0))


def fault_configs(rate: float) -> list[Config]:
    """Typos at ``rate`` under both noise laws, one and two cross distances,
    closed and one-way designs (one-way with one cross distance is refused
    before motion, so it is not run)."""
    out = []
    for plan_name, designs in (("closed", CLOSED), ("one-way", ONE_WAY)):
        for n_cross in (1, 2):
            if plan_name == "one-way" and n_cross == 1:
                continue
            for noise in ("gauss", "t3"):
                out.append(
                    Config(f"{plan_name} {n_cross}x {noise} typos", designs, n_cross, noise, rate)
                )
    return out


def clean_configs() -> list[Config]:
    """No typos, Gaussian tape: the false-alarm rate."""
    return [
        Config("closed 1x clean", CLOSED, 1, "gauss", 0.0),
        Config("closed 2x clean", CLOSED, 2, "gauss", 0.0),
        Config("one-way 2x clean", ONE_WAY, 2, "gauss", 0.0),
    ]


def description_for(n_cross: int, sigma_m: float = 0.001) -> RobotDescription:
    """The default screw layout with one (A->B) or two (A->B, B->C) cross distances."""
    base = default_description(sigma_m)
    pairs = (("A", "B"),) if n_cross == 1 else (("A", "B"), ("B", "C"))
    return RobotDescription(base.screws, base.sigma_m, pairs)


def transpose_digits(value_m: float, rng: np.random.Generator) -> float:
    """The reading in millimetres with one decimal, two adjacent differing digits swapped."""
    text = f"{value_m * 1000:.1f}"
    digits = [i for i, c in enumerate(text) if c.isdigit()]
    pairs = [(a, b) for a, b in itertools.pairwise(digits) if b == a + 1 and text[a] != text[b]]
    if not pairs:
        return value_m
    a, b = pairs[int(rng.integers(len(pairs)))]
    chars = list(text)
    chars[a], chars[b] = chars[b], chars[a]
    return float("".join(chars)) / 1000


class Operator:
    """Reads distances off the floor with tape noise and the odd typo."""

    def __init__(self, config: Config, sigma_m: float, rng: np.random.Generator) -> None:
        self.config = config
        self.sigma_m = sigma_m
        self.rng = rng
        self.typos = 0

    def read(self, exact_m: float) -> float:
        """One reading of a distance whose true value is ``exact_m``."""
        if self.config.noise == "t3":
            noise = self.sigma_m * float(self.rng.standard_t(3)) / math.sqrt(3.0)
        else:
            noise = self.sigma_m * float(self.rng.normal())
        value = abs(exact_m + noise)
        if self.rng.random() < self.config.typo_rate:
            self.typos += 1
            kind = int(self.rng.integers(len(TYPO_SHIFTS_M) + 1))
            if kind == len(TYPO_SHIFTS_M):
                value = transpose_digits(value, self.rng)
            else:
                value = abs(value + float(self.rng.choice((-1, 1))) * TYPO_SHIFTS_M[kind])
        return value


@dataclass
class Outcome:
    """One experiment."""

    config: str
    n_per_design: int
    values: np.ndarray | None = None
    stderr: np.ndarray | None = None
    low: np.ndarray | None = None
    high: np.ndarray | None = None
    wide_low: np.ndarray | None = None
    wide_high: np.ndarray | None = None
    status: str = "error"
    reasons: tuple[str, ...] = ()
    typos: int = 0
    remeasured: int = 0
    flagged: int = 0
    lost: int = 0
    ambiguous: list[int] = field(default_factory=list)
    spurious: list[tuple[int, float, bool]] = field(default_factory=list)
    typos_kept: int = 0


def belief_of(estimator: IncrementalEstimator, description: RobotDescription) -> ParameterBelief:
    """The running estimate as a belief, as the engine forms it."""
    priors = description.priors
    if estimator.fit is None:
        return ParameterBelief.from_priors(priors)
    try:
        result = estimator.result()
    except OdohilError:
        return ParameterBelief.from_priors(priors)
    return ParameterBelief.from_result(result, priors)


def run_experiment(
    config: Config, n_per_design: int, truth: ErrorParameters, rng: np.random.Generator
) -> Outcome:
    """One experiment of ``config`` with ``n_per_design`` trials of each design,
    the designs' trials interleaved as a session plan runs them in order."""
    description = description_for(config.n_cross)
    operator = Operator(config, description.sigma_m, rng)
    outcome = Outcome(config.name, n_per_design)
    designs = [Design(k, l_m) for k, l_m in config.designs]
    choreography = floor_choreography([(d, n_per_design) for d in designs])
    driven = [choreography.trial(t)[0] for t in range(1, choreography.n_trials + 1)]
    poses = {
        d: list(simulate(d.path(), truth, driven.count(d), seed=rng).pose_change)
        for d in dict.fromkeys(driven)
    }
    estimator = IncrementalEstimator()
    observations: list[Observation] = []
    trial = 0
    for design in driven:  # as a session drives them: one-way trials alternate direction
        odometry = design.path().encoder_end_pose()
        for pose in (poses[design].pop(0),):
            trial += 1
            exact = marks_from_pose(description, pose).as_array()
            readings = [operator.read(float(d)) for d in exact]
            rejections = remeasures = 0
            chosen = None
            while True:
                marks = MarkDistances.of(description, readings)
                predicted = predictive_pose(design, belief_of(estimator, description), odometry)
                try:
                    selection = select_pose(description, marks, odometry, predicted)
                except InconsistentMeasurementError:
                    rejections += 1
                    if rejections > MAX_REJECTIONS:
                        break
                    readings = [operator.read(float(d)) for d in exact]
                    continue
                if selection.slip.tripped and remeasures < MAX_REMEASURES:
                    remeasures += 1
                    outcome.remeasured += 1
                    readings[selection.slip.suspect] = operator.read(
                        float(exact[selection.slip.suspect])
                    )
                    continue
                chosen = selection
                break
            if chosen is None:
                outcome.lost += 1
                continue
            if chosen.slip.tripped:
                outcome.flagged += 1
            if chosen.ambiguous:
                outcome.ambiguous.append(trial)
                continue
            miss = _pose_miss(chosen.solution.pose_change, chosen.solution.cov, pose)
            if miss > SPURIOUS_D2:
                outcome.spurious.append((trial, miss, chosen.slip.tripped))
            if np.any(np.abs(np.array(readings) - exact) > TYPO_KEPT_M):
                outcome.typos_kept += 1
            observation = Observation(
                design, chosen.solution.pose_change, chosen.solution.cov, trial=trial
            )
            observations.append(observation)
            with contextlib.suppress(OdohilError):
                estimator.add(observation)
    outcome.typos = operator.typos
    try:
        result = estimate(observations, ambiguous=outcome.ambiguous)
    except OdohilError as exc:
        outcome.status = "failed"
        outcome.reasons = (str(exc),)
        return outcome
    outcome.values = np.array([p.value for p in result.parameters])
    outcome.stderr = np.array([p.stderr for p in result.parameters])
    outcome.low = np.array([p.ci95[0] for p in result.parameters])
    outcome.high = np.array([p.ci95[1] for p in result.parameters])
    outcome.wide_low = np.array([p.ci_4sigma[0] for p in result.parameters])
    outcome.wide_high = np.array([p.ci_4sigma[1] for p in result.parameters])
    outcome.status = result.verdict.status
    outcome.reasons = result.verdict.reasons
    return outcome


def _job(args: tuple[Config, int, int, int]) -> list[Outcome]:
    config, n_per_design, count, seed = args
    rng = np.random.default_rng(seed)
    return [run_experiment(config, n_per_design, NOMAD150, rng) for _ in range(count)]


def rate(hits: int, total: int) -> str:
    """``p +- SE`` in percent."""
    if total == 0:
        return "n/a"
    p = hits / total
    return f"{100 * p:.2f} % +- {100 * math.sqrt(max(p * (1 - p), 1.0 / total) / total):.2f}"


def _z(o: Outcome, true: np.ndarray) -> np.ndarray:
    """Per parameter, (estimate - truth) / reported SE (Wald)."""
    assert o.values is not None
    assert o.stderr is not None
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.asarray((o.values - true) / o.stderr)


def _log_z(o: Outcome, true: np.ndarray) -> np.ndarray:
    """Per parameter, the same on the log scale for K_theta and K_rho
    (log K - log truth) / (SE / K): the interval symmetric in log K."""
    z = _z(o, true)
    assert o.values is not None
    assert o.stderr is not None
    for i in (2, 3):
        if o.values[i] > 0:
            z[i] = (math.log(o.values[i]) - math.log(true[i])) / (o.stderr[i] / o.values[i])
    return z


def _outside(o: Outcome, true: np.ndarray) -> np.ndarray:
    """Per parameter: the truth outside the reported 4-sigma-equivalent
    interval (``wide``), or more than 4 SE away when none is reported."""
    if o.wide_low is not None and o.wide_high is not None:
        return np.asarray((true < o.wide_low) | (true > o.wide_high))
    return np.asarray(np.abs(_z(o, true)) > WRONG_SE)


def breakdown(trusted: Sequence[Outcome], true: np.ndarray) -> list[str]:
    """Confidently-wrong cases by parameter and by cause."""
    wrong = [o for o in trusted if bool(np.any(_outside(o, true)))]
    if not trusted:
        return []
    per_param = np.array([_outside(o, true) for o in trusted]).sum(axis=0)
    wald = np.array([np.abs(_z(o, true)) > WRONG_SE for o in trusted]).sum(axis=0)
    logs = np.array([np.abs(_log_z(o, true)) > WRONG_SE for o in trusted]).sum(axis=0)
    lines = [
        "  trusted and off, per parameter (E_R, E_T, K_theta, K_rho): reported interval "
        f"{per_param.tolist()}, Wald 4 SE {wald.tolist()}, log-scale 4 SE {logs.tolist()}"
    ]
    for o in wrong:
        z = _z(o, true)
        lz = _log_z(o, true)
        cause = []
        if o.spurious:
            cause.append(
                "spurious poses "
                + ", ".join(f"t{t} d2={d:.0f}{' flagged' if f else ''}" for t, d, f in o.spurious)
            )
        if o.typos_kept:
            cause.append(f"{o.typos_kept} trials keep a typo")
        if o.ambiguous:
            cause.append(f"{len(o.ambiguous)} ambiguous left out")
        if o.flagged:
            cause.append(f"{o.flagged} flagged kept")
        lines.append(
            "    wrong: z "
            + " ".join(f"{v:+.1f}" for v in z)
            + " | log-z K "
            + " ".join(f"{v:+.1f}" for v in lz[2:])
            + " | "
            + ("; ".join(cause) or "no fault found: the interval")
        )
    return lines


def summarise(outcomes: Sequence[Outcome], truth: ErrorParameters) -> list[str]:
    """The report's lines for one group of experiments."""
    true = np.array(truth.as_tuple())
    n = len(outcomes)
    estimated = [o for o in outcomes if o.values is not None]
    trusted = [o for o in estimated if o.status == "trusted"]
    wrong = [o for o in trusted if bool(np.any(_outside(o, true)))]
    lines = [
        f"  experiments {n}: trusted {len(trusted)}, doubtful "
        f"{sum(o.status == 'doubtful' for o in outcomes)}, failed "
        f"{sum(o.status == 'failed' for o in outcomes)}",
        f"  confidently wrong (trusted, the truth outside some reported "
        f"{WRONG_SE:g}-sigma interval): "
        f"{len(wrong)} = {rate(len(wrong), n)}",
        f"  not trusted: {rate(n - len(trusted), n)}",
    ]
    if estimated:
        low = np.array([o.low for o in estimated])
        high = np.array([o.high for o in estimated])
        cover = (low <= true) & (true <= high)
        cells = ", ".join(
            f"{name} {rate(int(c.sum()), len(estimated))}"
            for name, c in zip(PARAMETER_NAMES, cover.T, strict=True)
        )
        lines.append(f"  95 % coverage (all estimates): {cells}")
        values = np.array([o.values for o in estimated])
        bias = (values.mean(axis=0) - true) / true
        bias_se = values.std(axis=0, ddof=1) / math.sqrt(len(estimated)) / np.abs(true)
        lines.append(f"  K_theta relative bias {100 * bias[2]:+.2f} % +- {100 * bias_se[2]:.2f}")
    lines.append(
        f"  per experiment: typos {np.mean([o.typos for o in outcomes]):.2f}, re-measured "
        f"{np.mean([o.remeasured for o in outcomes]):.2f}, kept flagged "
        f"{np.mean([o.flagged for o in outcomes]):.3f}, lost "
        f"{np.mean([o.lost for o in outcomes]):.3f}, ambiguous left out "
        f"{np.mean([len(o.ambiguous) for o in outcomes]):.3f}"
    )
    lines += breakdown(trusted, true)
    with_ambiguous = [o for o in trusted if o.ambiguous]
    if with_ambiguous:
        off = sum(bool(np.any(_outside(o, true))) for o in with_ambiguous)
        inside = np.array(
            [(o.low <= true) & (true <= o.high) for o in with_ambiguous], dtype=float
        ).mean(axis=0)
        lines.append(
            f"  trusted with ambiguous trials left out: {len(with_ambiguous)}, of which "
            f"confidently wrong {off}; their 95 % coverage "
            + " / ".join(f"{v:.3f}" for v in inside)
        )
    reasons: dict[str, int] = {}
    for o in outcomes:
        for r in o.reasons:
            key = r.split(":")[0]
            reasons[key] = reasons.get(key, 0) + 1
    if reasons:
        lines.append("  reasons: " + "; ".join(f"{k} ({v})" for k, v in sorted(reasons.items())))
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--experiments", type=int, default=200, help="per configuration")
    parser.add_argument("--n-per-design", type=int, default=30)
    parser.add_argument("--typo-rate", type=float, default=0.01)
    parser.add_argument("--coverage-n", default="5,10,20,30")
    parser.add_argument(
        "--coverage-experiments", type=int, default=0, help="per n (0: skip the coverage table)"
    )
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--seed", type=int, default=20261123)
    parser.add_argument("--chunk", type=int, default=5)
    parser.add_argument(
        "--clean-experiments", type=int, default=None, help="per clean configuration"
    )
    parser.add_argument(
        "--max-seconds",
        type=float,
        default=None,
        help="stop after this wall time and report what is done (jobs run in shuffled order)",
    )
    args = parser.parse_args()

    for config in fault_configs(args.typo_rate) + clean_configs():
        problems = redundancy_problems(
            description_for(config.n_cross), [Design(k, l_m) for k, l_m in config.designs]
        )
        assert not problems, problems
    groups: list[tuple[str, Config, int, int]] = [
        ("faults", c, args.n_per_design, args.experiments) for c in fault_configs(args.typo_rate)
    ]
    clean = args.experiments if args.clean_experiments is None else args.clean_experiments
    groups += [("clean", c, args.n_per_design, clean) for c in clean_configs()]
    if args.coverage_experiments:
        for n in (int(v) for v in args.coverage_n.split(",")):
            groups.append(
                (
                    "coverage",
                    Config(f"paper designs n={n} clean 1x", CLOSED, 1, "gauss", 0.0),
                    n,
                    args.coverage_experiments,
                )
            )
            groups.append(
                (
                    "coverage",
                    Config(f"paper designs n={n} t3 1x", CLOSED, 1, "t3", 0.0),
                    n,
                    args.coverage_experiments,
                )
            )
    seeds = iter(np.random.SeedSequence(args.seed).generate_state(100_000))
    jobs = []
    for _, config, n, total in groups:
        left = total
        while left > 0:
            jobs.append((config, n, min(args.chunk, left), int(next(seeds))))
            left -= args.chunk
    print(f"command: python bench/operator_faults.py {' '.join(sys.argv[1:])}")
    print(
        f"load average before: {os.getloadavg()[0]:.2f}; {args.workers} workers; "
        f"{sum(g[3] for g in groups)} experiments",
        flush=True,
    )
    start = time.perf_counter()
    results: dict[tuple[str, int], list[Outcome]] = {}
    done = 0
    order = np.random.default_rng(args.seed).permutation(len(jobs))
    jobs = [jobs[i] for i in order]
    with multiprocessing.Pool(args.workers) as pool:
        for chunk in pool.imap_unordered(_job, jobs):
            for o in chunk:
                results.setdefault((o.config, o.n_per_design), []).append(o)
            done += len(chunk)
            print(f"{done} experiments, {time.perf_counter() - start:.0f} s", file=sys.stderr)
            if args.max_seconds is not None and time.perf_counter() - start > args.max_seconds:
                print(f"stopped at --max-seconds {args.max_seconds:g}: {done} done", flush=True)
                pool.terminate()
                break
    totals: dict[str, list[Outcome]] = {}
    for kind, config, n, _ in groups:
        outcomes = results.get((config.name, n), [])
        totals.setdefault(kind, []).extend(outcomes)
        print(f"[{kind}] {config.name}, n = {n} per design")
        for line in summarise(outcomes, NOMAD150):
            print(line)
    for kind in ("faults", "clean"):
        outcomes = totals.get(kind, [])
        print(f"== all {kind} configurations together")
        for line in summarise(outcomes, NOMAD150):
            print(line)
    print(
        f"wall clock {time.perf_counter() - start:.0f} s, load average after: "
        f"{os.getloadavg()[0]:.2f}",
        flush=True,
    )


if __name__ == "__main__":
    main()
