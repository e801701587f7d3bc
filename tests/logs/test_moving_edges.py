"""Trials whose cut is given and that move at once (issue 30, part 1): an
optiodom run or a labelled trial that starts moving at its first or second
sample starts at its first sample; one that ends moving ends at its last;
``--min-edge-rest 0`` is accepted."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from odohil.errors import ParameterError
from odohil.session.robots.description import load_robot_description
from odohil.session.trials.logs import ImportOptions, read_recording
from odohil.session.trials.logs.csv_log import write_csv_log
from odohil.session.trials.logs.optiodom import optiodom_geometry
from odohil.session.trials.logs.recording import Recording
from tests.logs.data import optiodom_robot
from tests.logs.synth import Motion, rest, synth_log

COUNTS = 40
"""Counts per 50 ms cycle of each wheel on a synthetic optiodom straight run."""
SCALE = 1.01
"""The true robot drives this much farther than its odometry says."""


def _optiodom_session(root: Path, first_moving: int, rest_rows: int = 20) -> Path:
    """A session folder of one straight run in the optiodom layout (its
    README): idle rows before ``first_moving``, 60 moving rows, a rest."""
    session = "010120260000"
    folder = root / "square" / session
    folder.mkdir(parents=True)
    (folder / f"{session}_metadata.csv").write_text(
        "type,diff,,\nngear,43.7,,\nencRes,64,,\nLi,0.2,,\nDi,0.084,0.084,\nN,1,,\n"
    )
    counts = [0] * first_moving + [COUNTS] * 60 + [0] * rest_rows
    per_count = optiodom_geometry().metres_per_count
    rng = np.random.default_rng(3)
    rows, travelled = [], 0.0
    for index, count in enumerate(counts):
        travelled += count * per_count
        x = SCALE * travelled + rng.normal(0.0, 6e-5)
        y, theta = rng.normal(0.0, 6e-5), rng.normal(0.0, 7e-4)
        rows.append(f"{0.05 * index!r},{x!r},{y!r},{theta!r},{count},{count}")
    (folder / f"{session}_run-01.csv").write_text("\n".join(rows) + "\n")
    return root


@pytest.mark.parametrize("first_moving", [0, 1])
def test_an_optiodom_run_that_moves_at_once_starts_at_its_first_sample(
    tmp_path: Path, first_moving: int
) -> None:
    root = _optiodom_session(tmp_path, first_moving)
    for options in (
        ImportOptions(format="optiodom"),
        ImportOptions(format="optiodom", min_edge_rest_s=0.0),
    ):
        (trial,) = read_recording([root], optiodom_robot(), options)
        per_count = optiodom_geometry().metres_per_count
        # the path runs from the first sample: its own increment is before it
        driven = (60 - (1 if first_moving == 0 else 0)) * COUNTS * per_count
        assert trial.family == "straight"
        assert math.isclose(trial.path.distance_m, driven, rel_tol=1e-6)
        assert abs(trial.pose_change[0] - SCALE * driven) < 5e-4
        assert trial.span_s is not None
        assert trial.span_s[0] == 0.0
        # the single start sample's covariance is the end rest's per-sample scatter
        assert 1e-5 < math.sqrt(trial.measurement_cov[0, 0]) < 2e-4


def _labelled_log(tmp_path: Path, drop_first: bool, end_moving: bool) -> tuple[Path, float]:
    motions = [Motion(3.0, v=0.2)] + ([] if end_moving else [rest(1.0)])
    log = synth_log(motions, turn_scale=0.0)
    keep = slice(1 if drop_first else 0, None)
    t, odometry, truth = log.t_s[keep], log.odometry[keep], log.truth[keep]
    path = tmp_path / "log.csv"
    lines = np.arange(2, 2 + len(t))
    write_csv_log(path, Recording("synthetic", t, odometry, truth, lines, trial=("a",) * len(t)))
    odometry_end = float(log.odometry[-1, 0] - odometry[0, 0])
    return path, odometry_end


@pytest.mark.parametrize(
    ("drop_first", "end_moving"), [(False, False), (True, False), (False, True)]
)
def test_a_labelled_trial_that_moves_at_once_starts_at_its_first_sample(
    tmp_path: Path, drop_first: bool, end_moving: bool
) -> None:
    path, driven = _labelled_log(tmp_path, drop_first, end_moving)
    robot = tmp_path / "robot.toml"
    robot.write_text(
        '[robot]\nprotocol = "recorded"\ncounts_per_rev = 1000\n'
        "wheel_diameter_m = [0.1, 0.1]\nwheel_base_m = 0.25\n"
        "[screws]\nA = [0.1, 0.0]\nB = [-0.05, 0.08]\nC = [-0.05, -0.08]\n"
        "[measurement]\nsigma_m = 0.001\npose_sigma = [0.0001, 0.0001, 0.001]\n"
    )
    description = load_robot_description(robot)
    for edge in (0.2, 0.0):
        options = ImportOptions(format="csv", min_edge_rest_s=edge)
        (trial,) = read_recording([path], description, options)
        assert trial.family == "straight"
        assert math.isclose(trial.path.distance_m, driven, rel_tol=1e-9)
        assert abs(trial.pose_change[0] - 1.01 * driven) < 1e-3


def test_a_negative_min_edge_rest_is_refused() -> None:
    with pytest.raises(ParameterError, match="--min-edge-rest must be zero or a positive"):
        ImportOptions(min_edge_rest_s=-0.1)
