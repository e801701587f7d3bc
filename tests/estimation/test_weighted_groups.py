"""The robust fit's weighted groups are the groups TrialGroup.add builds, bit for bit."""

from __future__ import annotations

import numpy as np

from odohil.science.estimators.observations import Observation, TrialGroup
from odohil.science.estimators.robust import weighted_groups
from odohil.science.paths import Design


def _added(
    observations: list[Observation], weights: np.ndarray, references: dict[Design, float]
) -> list[TrialGroup]:
    groups: dict[tuple[Design, bytes], TrialGroup] = {}
    for obs, weight in zip(observations, weights, strict=True):
        key = (obs.design, obs.measurement_cov.tobytes())
        if key not in groups:
            groups[key] = TrialGroup(obs.design, references[obs.design])
        groups[key].add(obs, float(weight))
    return list(groups.values())


def test_weighted_groups_are_trial_group_add_bit_for_bit() -> None:
    rng = np.random.default_rng(5)
    designs = [Design(1, 6.0), Design(20, 0.5), Design(2, 1.0, "reverse")]
    covs = [np.zeros((3, 3)), np.diag([1e-6, 2e-6, 3e-5])]
    observations = [
        Observation(
            designs[int(rng.integers(3))],
            np.array([rng.normal(0, 0.05), rng.normal(0, 0.05), rng.normal(3.0, 0.5)]),
            covs[int(rng.integers(2))],
        )
        for _ in range(40)
    ]
    references = {d: float(rng.normal(3.0, 0.2)) for d in designs}
    for weights in (np.ones(40), rng.uniform(0.01, 1.0, 40)):
        new = weighted_groups(observations, weights, references)
        old = _added(observations, weights, references)
        assert len(new) == len(old) == 6
        for a, b in zip(new, old, strict=True):
            assert (a.design, a.reference, a.n, a.weight) == (b.design, b.reference, b.n, b.weight)
            for x, y in (
                (a.total, b.total),
                (a.outer, b.outer),
                (a.measurement_total, b.measurement_total),
            ):
                assert x.shape == y.shape
                assert x.tobytes() == y.tobytes()
