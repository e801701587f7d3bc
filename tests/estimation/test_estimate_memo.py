"""estimate() computes the same trials with the same arguments once per process
(odohil/science/estimators/estimate.py): anything it reads changes the result."""

from __future__ import annotations

import numpy as np

from odohil.science.estimators import Observation, estimate
from odohil.science.estimators.checks import Criteria
from odohil.science.estimators.estimate import _MEMO_SIZE, _memo
from odohil.science.parameters import NOMAD150
from odohil.science.paths import Design
from odohil.science.simulator import simulate


def _trials() -> list[Observation]:
    out: list[Observation] = []
    for design in (Design(1, 3), Design(10, 0.5)):
        for pose in simulate(design.path(), NOMAD150, 10, seed=4).pose_change:
            out.append(Observation(design, pose, np.eye(3) * 1e-6, trial=len(out) + 1))
    return out


def test_the_same_trials_are_estimated_once() -> None:
    trials = _trials()
    first = estimate(trials)
    again = estimate([Observation(o.design, o.pose_change.copy(), o.measurement_cov.copy(),
                                  trial=o.trial) for o in trials])  # fmt: skip
    assert again is first


def test_whatever_estimate_reads_gives_another_result() -> None:
    trials = _trials()
    first = estimate(trials)
    moved = [*trials]
    moved[0] = Observation(trials[0].design, trials[0].pose_change + 1e-9,
                           trials[0].measurement_cov, trial=1)  # fmt: skip
    renumbered = [Observation(o.design, o.pose_change, o.measurement_cov, trial=o.trial + 100)
                  for o in trials]  # fmt: skip
    others = [
        estimate(moved),
        estimate(renumbered),
        estimate(trials, method="joint"),
        estimate(trials, exclude=[3]),
        estimate(trials, ambiguous=[21]),
        estimate(trials, turns_exact=False),
        estimate(trials, criteria=Criteria(e_r_relative=0.01)),
    ]
    assert all(o is not first for o in others)
    assert others[3].excluded == (3,)
    assert [t.trial for t in others[1].trials][:2] == [101, 102]


def test_the_memo_keeps_the_last_few() -> None:
    trials = _trials()
    for k in range(_MEMO_SIZE + 3):
        estimate(trials, exclude=[k + 1])
    assert len(_memo) == _MEMO_SIZE
