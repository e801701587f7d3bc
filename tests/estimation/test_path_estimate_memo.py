"""estimate_paths() computes the same general-path trials with the same
arguments once per process (odohil/science/estimators/paths.py): a validation,
a report and the wizard's next question estimate one calibration again.
Anything it reads changes the result."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from odohil.science.estimators.paths import estimate_paths
from odohil.science.parameters import NOMAD150
from odohil.science.path_designs import PathDesign
from odohil.science.path_trials import PathTrial
from odohil.science.paths import Design
from odohil.science.simulator import simulate


def _trials() -> list[PathTrial]:
    out: list[PathTrial] = []
    for path in (Design(1, 3).path(), PathDesign("square", 4, 1.0, True).path()):
        for pose in simulate(path, NOMAD150, 12, seed=4).pose_change:
            out.append(PathTrial(path, pose, np.eye(3) * 1e-6, family=path.name or "p"))
    return out


def test_the_same_trials_are_estimated_once() -> None:
    trials = _trials()
    first = estimate_paths(trials, turns_exact=True, method="joint")
    copies = [replace(t, pose_change=t.pose_change.copy()) for t in trials]
    assert estimate_paths(copies, turns_exact=True, method="joint") is first


def test_anything_it_reads_changes_the_result() -> None:
    trials = _trials()
    first = estimate_paths(trials, turns_exact=True, method="joint")
    moved = [replace(trials[0], pose_change=trials[0].pose_change + 1e-4), *trials[1:]]
    assert estimate_paths(moved, turns_exact=True, method="joint") is not first
    assert estimate_paths(trials, turns_exact=True, method="robust") is not first
    assert estimate_paths(trials, turns_exact=True, method="joint", exclude=[3]) is not first
    assert estimate_paths(trials, turns_exact=True, method="joint", intervals="wald") is not first
    renamed = [replace(trials[0], family="other"), *trials[1:]]
    assert estimate_paths(renamed, turns_exact=True, method="joint") is not first
