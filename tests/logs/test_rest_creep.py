"""A rest's odometry may creep within the edge tolerances (gear backlash as
the wheels start and stop: 1-2 mm on the optiodom robot). The trial's path and
its measured pose change must then cover the same time; the reader once left
the creep out of the path while averaging the ground truth over it, which
biased E_T on the June straight runs (-0.17 % against -0.25 %, issue 20)."""

from __future__ import annotations

import numpy as np
import pytest

from odohil.session.trials.logs.recording import ImportOptions, Recording, trials_of
from tests.logs.data import optiodom_robot


def _run(creep_m: float) -> Recording:
    """A perfect robot (odometry = truth) driving 1 m straight with a trial
    column: a 2 s rest, ``creep_m`` crept over 0.3 s, the run, 0.3 s of creep
    at the end again, a 2 s rest; 20 Hz."""
    rest = np.zeros(40)
    creep = np.linspace(0.0, creep_m, 7)[1:]
    run = np.linspace(creep_m, 1.0 - creep_m, 100)[1:]
    end_creep = np.linspace(1.0 - creep_m, 1.0, 7)[1:]
    x = np.concatenate([rest, creep, run, end_creep, np.full(40, 1.0)])
    t = np.arange(len(x)) * 0.05
    poses = np.column_stack([x, np.zeros_like(x), np.zeros_like(x)])
    return Recording(
        "creep.csv",
        t,
        poses,
        poses.copy(),
        np.arange(2, 2 + len(x), dtype=np.int64),
        trial=("run",) * len(x),
    )


@pytest.mark.parametrize("creep_m", [0.0, 0.001, 0.0014])
def test_the_path_and_the_pose_change_cover_the_same_time(creep_m: float) -> None:
    (trial,) = trials_of(_run(creep_m), optiodom_robot(), ImportOptions())
    # a perfect robot: what the odometry drove is what the truth saw
    assert trial.path.distance_m == pytest.approx(1.0, abs=1e-9)
    assert trial.pose_change[0] == pytest.approx(1.0, abs=1e-9)
