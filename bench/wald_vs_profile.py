"""Why clean data looked 'confidently wrong': Wald SE against the reported interval.

Usage: ``python bench/wald_vs_profile.py [--seeds 400] [--n 5]``

For each seed: n exact trials of each paper design (Nomad 150 values), the
Cox-Reid adjusted joint fit, and each parameter's distance from the truth in
Wald standard errors. Every data set with some parameter more than 4 Wald SE
off is estimated again with ``estimate(..., "joint")`` and checked against the
interval the user is given (``ci_4sigma``: profile likelihood for K_theta and
K_rho, Satterthwaite t for E_R and E_T; docs/estimation.md). Prints each such
case (z per parameter, estimate / truth, inside the reported interval or not)
and the counts.
"""

from __future__ import annotations

import argparse

import numpy as np

from odohil.science.estimators import Observation, estimate
from odohil.science.estimators.estimate import fit_joint
from odohil.science.estimators.observations import group_trials, summarise
from odohil.science.estimators.paper import paper_estimate
from odohil.science.parameters import NOMAD150, PARAMETER_NAMES
from odohil.science.paths import Design
from odohil.science.simulator import simulate

DESIGNS = (Design(1, 6.0), Design(20, 0.5))


def trials(n: int, seed: int) -> list[Observation]:
    """n exact trials of each design."""
    rng = np.random.default_rng(seed)
    out = []
    for design in DESIGNS:
        for pose in simulate(design.path(), NOMAD150, n, seed=rng, segment_m=0.05).pose_change:
            out.append(Observation(design, pose))
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--seeds", type=int, default=400)
    parser.add_argument("--n", type=int, default=5)
    args = parser.parse_args()
    truth = np.array(NOMAD150.as_tuple())
    wald = np.zeros(4, dtype=int)
    cases = outside = 0
    for seed in range(args.seeds):
        obs = trials(args.n, seed)
        groups = group_trials(obs)
        fit = fit_joint(groups, paper_estimate(summarise(groups)))
        z = (np.array(fit.params.as_tuple()) - truth) / np.sqrt(np.diag(fit.covariance))
        off = np.abs(z) > 4
        if not off.any():
            continue
        cases += 1
        wald += off
        result = estimate(obs, "joint")
        inside = [p.contains(t) for p, t in zip(result.parameters, truth, strict=True)]
        outside += not all(inside)
        ratio = " ".join(
            f"{p.value / t:.2f}" for p, t in zip(result.parameters, truth, strict=True)
        )
        print(f"seed {seed}: z {np.round(z, 1)}, estimate/truth {ratio}, inside {inside}")
    print(
        f"{cases} of {args.seeds} data sets have a parameter > 4 Wald SE off "
        f"(per parameter {dict(zip(PARAMETER_NAMES, wald.tolist(), strict=True))}); "
        f"{outside} of them have the truth outside the reported 4-sigma interval"
    )


if __name__ == "__main__":
    main()
