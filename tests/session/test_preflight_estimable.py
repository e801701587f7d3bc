"""Pre-flight refuses a plan the estimator cannot use (issue 17, item 5).

Before: a Create 2 plan of reverse trials only (``k=1,l=1,n=2``: every trial
ends at its start, signed distance 0, so the mean heading change says nothing
of E_R) was driven in full and then ended "no estimate ... paper's method",
exit 1; so was a one-trial plan on the Nomad. Now ``run`` refuses both before
any folder is made or port opened, exit 2, saying why and what would make the
plan estimable. The rule is the estimator's own
(odohil/science/estimators/checks.py ``plan_problems``): the test below holds
it to what ``estimate`` does with simulated trials of the same plans.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from odohil.cli.app import app
from odohil.errors import MeasurementError
from odohil.science.estimators import estimate
from odohil.science.estimators.checks import plan_problems
from odohil.science.estimators.observations import Observation
from odohil.science.parameters import NOMAD150
from odohil.science.simulator import simulate
from odohil.session.plan import parse_plan


def _run(*args: str) -> tuple[int, str]:
    result = CliRunner().invoke(app, ["run", *args])
    assert result.exception is None or isinstance(result.exception, SystemExit), repr(
        result.exception
    )
    return result.exit_code, " ".join(result.stderr.split())


@pytest.mark.parametrize(
    ("plan", "variant"),
    [
        ("k=1,l=1,n=2", "reverse"),
        ("k=1,l=1,n=3;k=5,l=0.5,n=3", "reverse"),
        ("k=1,l=1,n=1", "turn"),
        ("k=0.5,l=1,n=1;k=1,l=1,n=1", "turn"),
        ("k=0.5,l=1,n=2", "reverse"),
        ("k=1,l=1,n=2", "turn"),
        ("k=1,l=2,n=3;k=0.5,l=2,n=3", "reverse"),
    ],
)
def test_the_check_agrees_with_the_estimator(plan: str, variant: str) -> None:
    """Refused exactly when simulated trials of the plan give no estimate."""
    items = parse_plan(plan, variant).items
    problems = plan_problems([(i.design, i.n_trials) for i in items], NOMAD150)
    observations = []
    for seed, item in enumerate(items):
        poses = simulate(item.design.path(), NOMAD150, item.n_trials, seed=seed).pose_change
        noisy = poses + np.random.default_rng(seed).normal(0.0, 1e-3, poses.shape)
        observations += [Observation(item.design, pose) for pose in noisy]
    if problems:
        with pytest.raises(MeasurementError):
            estimate(observations, "joint")
    else:
        estimate(observations, "joint")  # an estimate, whatever its verdict


@pytest.mark.parametrize(
    ("robot", "port", "plan", "said"),
    [
        (  # reverse trials only: each ends at its start
            "create2",
            "fakecreate2://?seed=1&time_scale=20",
            "k=1,l=1,n=2",
            [
                "--plan k=1,l=1,n=2,variant=reverse: no estimate could come of these trials",
                "signed distance 0 m",
                "e.g. k=0.5,l=1,n=2",  # what would make it estimable
            ],
        ),
        (  # one trial: no sample variance
            "nomad150",
            "fakerobot://?seed=1&time_scale=50",
            "k=1,l=1,n=1",
            ["k=1 l=1 m turn: 1 trial", "n=2 or more for k=1 l=1 m turn"],
        ),
    ],
)
def test_a_plan_the_estimator_cannot_use_is_refused_before_anything_moves(
    tmp_path: Path, robot: str, port: str, plan: str, said: list[str]
) -> None:
    folder = tmp_path / "session"
    code, err = _run(
        "--port", port, "--robot", robot, "--plan", plan, "--measure", "fake",
        "--session", str(folder),
    )  # fmt: skip
    assert code == 2, err
    for words in said:
        assert words in err, err
    assert not folder.exists()  # nothing journaled: no session, no port opened
