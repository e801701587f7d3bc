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
from odohil.errors import MeasurementError, ParameterError
from odohil.robots import __file__ as robots_init
from odohil.science.estimators import estimate
from odohil.science.estimators.checks import plan_problems
from odohil.science.estimators.observations import Observation
from odohil.science.parameters import NOMAD150
from odohil.science.path_designs import parse_path_design
from odohil.science.paths import Design, square
from odohil.science.simulator import simulate
from odohil.session.plans.checks import check_estimable, check_turns, estimability, turn_designs
from odohil.session.plans.plan import Plan, PlanItem, parse_plan
from odohil.session.robots.description import read_robot_toml
from odohil.session.robots.registry import parse_description
from odohil.session.run import SessionSpec, preflight

ROBOTS = Path(robots_init).parent


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


# --- what a plan can and cannot estimate (issue 19, deliverable 4) -----------------


def _estimable_check(tmp_path: Path, robot: str, port: str, plan: str, **more: object) -> str:
    spec = SessionSpec(
        tmp_path / "session",
        robot_path=ROBOTS / f"{robot}.toml",
        plan=plan,
        measure="fake",
        port=port,
        **more,
    )
    checks = {c.name: c for c in preflight(spec).checks}
    assert checks["plan estimable"].passed, checks["plan estimable"].message
    return checks["plan estimable"].message


def test_the_preflight_says_a_turn_free_plan_cannot_estimate_the_turn_errors(
    tmp_path: Path,
) -> None:
    said = _estimable_check(
        tmp_path, "create2", "fakecreate2://?seed=1", "k=0.5,l=1,n=10;k=2,l=1,n=10"
    )
    assert said.startswith("Estimates E_R (SE ")
    assert "Cannot estimate e_turn_spin: the plan makes no spins (turns in place)" in said
    assert "K_spin: the plan makes no spins" in said
    assert "e_turn_arc: the plan makes no arcs" in said


def test_the_preflight_says_forth_and_back_turn_designs_fold_the_turn_errors(
    tmp_path: Path,
) -> None:
    """On a robot whose turns carry error, forth-and-back sessions are
    estimated with the four parameters: the statement says the turn errors
    are not estimated but folded into E_R and K_theta."""
    said = _estimable_check(
        tmp_path,
        "create2",
        "fakecreate2://?seed=1",
        "k=0.5,l=1,n=10,variant=reverse;k=1,l=1,n=10,variant=turn",
        allow_turns=True,
    )
    assert "e_turn_spin: not fitted by the forth-and-back estimator (folded into E_R" in said
    assert "name the turns as paths" in said


def test_the_preflight_of_a_robot_whose_turns_are_exact_says_so(tmp_path: Path) -> None:
    said = _estimable_check(
        tmp_path, "nomad150", "fakerobot://?seed=1", "k=1,l=6,n=30;k=20,l=0.5,n=30"
    )
    assert said.startswith("Estimates E_R (SE ")
    assert "Turns declared exact ([robot] turns_exact): no turn errors in the model" in said


def test_a_plan_of_squares_on_a_create2_estimates_its_turn_errors() -> None:
    """A plan naming general paths is estimated from general paths with the
    turn errors (odohil/session/results/outcome.py): the statement names them
    estimated with the four, and what the paths leave out."""
    description = parse_description(
        read_robot_toml(ROBOTS / "create2.toml", what="robot"), "create2.toml"
    )
    items = [
        (parse_path_design("square:1.0,ccw"), 10),
        (parse_path_design("square:1.0,cw"), 10),
        (Design(0.5, 1.0, "reverse"), 10),
    ]
    statement = estimability(items, description)
    assert statement.ok
    assert statement.estimable == ("E_R", "E_T", "K_theta", "K_rho", "e_turn_spin", "K_spin")
    assert "the turn errors with the four (not folded into E_R and K_theta)" in statement.text()
    assert "Cannot estimate e_turn_arc: the plan makes no arcs" in statement.text()
    too_few = estimability([(square(1.0, True), 2), (square(1.0, False), 2)], description)
    assert not too_few.ok
    assert too_few.problems == ("4 trials for 6 parameters: need at least 7",)


def test_a_plan_item_naming_squares_passes_the_turn_check_and_is_stated() -> None:
    """A plan item may be a path design (odohil/science/path_designs.py): a
    plan naming one is estimated from general paths with the turn errors, so
    the turn check leaves it and its turn designs alone, and the
    estimability check states the turn errors estimated."""
    description = parse_description(
        read_robot_toml(ROBOTS / "create2.toml", what="robot"), "create2.toml"
    )
    plan = Plan(
        (
            PlanItem(parse_path_design("square:1,ccw"), 10),  # type: ignore[arg-type]
            PlanItem(parse_path_design("square:1,cw"), 10),  # type: ignore[arg-type]
            PlanItem(Design(0.5, 1.0, "reverse"), 10),
            PlanItem(Design(1, 1.0, "turn"), 10),
        )
    )
    assert turn_designs(plan, description) == []  # estimated with the turn errors too
    check_turns(plan, description, allow_turns=False)
    statement = check_estimable(plan, description)
    assert statement is not None
    assert statement.estimable[-2:] == ("e_turn_spin", "K_spin")
    assert "folded" not in statement.text().replace("not folded", "")


def test_a_plan_naming_paths_that_cannot_give_an_estimate_is_refused() -> None:
    description = parse_description(
        read_robot_toml(ROBOTS / "create2.toml", what="robot"), "create2.toml"
    )
    plan = Plan(
        (
            PlanItem(parse_path_design("square:1,ccw"), 3),  # type: ignore[arg-type]
            PlanItem(parse_path_design("square:1,cw"), 3),  # type: ignore[arg-type]
        )
    )
    with pytest.raises(ParameterError) as refused:
        check_estimable(plan, description)
    said = str(refused.value)
    assert said.startswith(
        "--plan (square 1 m ccw n=3; square 1 m cw n=3): no estimate could come of these trials"
    )
    assert "6 trials for 6 parameters: need at least 7. What they would give: Estimates" in said
