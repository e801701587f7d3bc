"""Benchmark of the discrete-model simulator: segment-steps per second on one core.

Usage: ``python bench/simulator.py [--repeat R] [--seconds S]``

A segment-step is one trial driving one segment, so the figure is
trials x segments / wall-clock seconds. Run on one core: the script pins the
BLAS/OpenMP thread pools to one thread before numpy is imported (the
simulator does not use them, but this keeps the measurement honest).
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import time  # noqa: E402

from odohil.science.parameters import NOMAD150  # noqa: E402
from odohil.science.paths import Design  # noqa: E402
from odohil.science.simulator import DEFAULT_SEGMENT_M, segments_per_leg, simulate  # noqa: E402

DESIGNS = (Design(1, 6.0, "turn"), Design(20, 0.5, "turn"))


def rate(design: Design, seconds: float, seed: int) -> tuple[float, int]:
    """Best-effort steps/s for one design: run about ``seconds`` of trials, once."""
    per_trial = design.n_legs * segments_per_leg(design.l_m, DEFAULT_SEGMENT_M)
    path = design.path()
    simulate(path, NOMAD150, 64, seed=seed)  # warm-up: page in code and buffers
    n_trials = 256
    start = time.perf_counter()
    simulate(path, NOMAD150, n_trials, seed=seed)
    elapsed = time.perf_counter() - start
    n_trials = max(256, int(n_trials * seconds / elapsed))
    start = time.perf_counter()
    simulate(path, NOMAD150, n_trials, seed=seed)
    elapsed = time.perf_counter() - start
    return n_trials * per_trial / elapsed, n_trials


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3, help="runs per design; best is kept")
    parser.add_argument("--seconds", type=float, default=2.0, help="target seconds per run")
    args = parser.parse_args()
    print(f"segment length {DEFAULT_SEGMENT_M} m, Nomad 150 parameters, one thread")
    print(f"load average before: {os.getloadavg()[0]:.2f}")
    for design in DESIGNS:
        rates = []
        n_trials = 0
        for repeat in range(args.repeat):
            value, n_trials = rate(design, args.seconds, seed=repeat)
            rates.append(value)
        shown = ", ".join(f"{r:.3g}" for r in rates)
        print(
            f"{design.label():>22}: best {max(rates):.3g} segment-steps/s "
            f"({n_trials} trials/run; all runs: {shown})"
        )
    print(f"load average after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
