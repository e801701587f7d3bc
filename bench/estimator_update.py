"""Time one IncrementalEstimator update at 200 trials (target: at most 20 ms).

Usage: python bench/estimator_update.py

200 simulated trials (the paper's designs A and B, 100 each, 1 mm / 0.3 deg
measurement noise) are added first; then 40 more, one at a time, and the
time of each update is recorded, both for the fit alone
(``IncrementalEstimator.add``) and for the whole live update
(``add`` plus ``result().to_json_dict()``: the model check, sufficiency and
verdict the live display and journal get, as in
odohil/session/run/engine.py's IncrementalLiveEstimator). Prints the median and
the maximum of each.
"""

from __future__ import annotations

import os
import statistics
import time

import numpy as np

from odohil.science.estimators import IncrementalEstimator, Observation
from odohil.science.parameters import NOMAD150
from odohil.science.paths import Design
from odohil.science.simulator import simulate


def main() -> None:
    rng = np.random.default_rng(7)
    designs = (Design(1, 6.0), Design(20, 0.5))
    meas = np.diag([1e-6, 1e-6, np.radians(0.3) ** 2])
    trials: list[Observation] = []
    for design in designs:
        poses = simulate(design.path(), NOMAD150, 120, seed=rng, segment_m=0.01).pose_change
        noise = rng.multivariate_normal(np.zeros(3), meas, size=len(poses))
        trials += [Observation(design, p, meas) for p in poses + noise]
    order = rng.permutation(len(trials))
    trials = [trials[i] for i in order]
    estimator = IncrementalEstimator()
    for trial in trials[:200]:
        estimator.add(trial)
    times = []
    live = []
    cpu = []
    for trial in trials[200:240]:
        start = time.perf_counter()
        start_cpu = time.process_time()
        estimator.add(trial)
        times.append(time.perf_counter() - start)
        estimator.result().to_json_dict()
        live.append(time.perf_counter() - start)
        cpu.append(time.process_time() - start_cpu)
    fit = estimator.fit
    assert fit is not None
    print(f"trials: {estimator.n_trials}, groups: {len(estimator.groups)}")
    print(
        f"update time at 200+ trials: median {1e3 * statistics.median(times):.1f} ms, "
        f"max {1e3 * max(times):.1f} ms (over {len(times)} updates)"
    )
    print(
        f"live update (fit + result JSON with verdict): median "
        f"{1e3 * statistics.median(live):.1f} ms, max {1e3 * max(live):.1f} ms"
    )
    print(
        f"live update CPU time (this process only; wall time grows with the machine's "
        f"load): median {1e3 * statistics.median(cpu):.1f} ms, max {1e3 * max(cpu):.1f} ms"
    )
    print(f"load average: {os.getloadavg()[0]:.2f}")
    print(f"estimate (paper units): {fit.params.to_paper_units()}")


if __name__ == "__main__":
    main()
