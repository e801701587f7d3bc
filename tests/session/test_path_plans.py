"""Plans that name general paths (issue 19, deliverable 3): the ``path=`` syntax
and its round trips through the text and the journal's plan record, the
trials' numbering beside forth-and-back designs, the floor a closed path
needs, and a session of squares driven, journaled and estimated by the
general-path recipe over both backends' in-process fakes."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import fakes
from odohil.errors import ParameterError
from odohil.robots import __file__ as robots_init
from odohil.science.floor_marks import PosePrior
from odohil.science.path_designs import PathDesign, parse_path_design
from odohil.science.paths import Design
from odohil.session.journal.state import load_session, session_path_trials
from odohil.session.measure.plausibility import judge
from odohil.session.measure.protocol import MeasuredPose
from odohil.session.plans.checks import check_floor
from odohil.session.plans.plan import Plan, parse_plan, path_floor_m
from odohil.session.results.outcome import estimate_state
from odohil.session.robots.registry import parse_description
from odohil.session.run import SessionSpec, open_session, preflight, require, run_session
from odohil.session.run.start_pose import StartPose

ROBOTS = Path(robots_init).parent


@pytest.fixture(autouse=True)
def _fake_urls() -> None:
    fakes.register_url_handlers()


def test_a_plan_names_general_paths_and_round_trips() -> None:
    plan = parse_plan("path=square:1.0,cw,n=10;k=1,l=2,n=10;n=4,path=circle:0.5,8")
    shapes = [item.design for item in plan.items]
    assert shapes == [
        parse_path_design("square:1,cw"),
        Design(1.0, 2.0, "turn"),
        PathDesign("circle", 8, 0.5, True),
    ]
    assert [item.n_trials for item in plan.items] == [10, 10, 4]
    text = plan.to_text()
    assert text == "path=square:1,cw,n=10;k=1,l=2,n=10,variant=turn;path=circle:0.5,8,ccw,n=4"
    assert parse_plan(text) == plan
    assert Plan.from_json(plan.to_json()) == plan
    assert plan.to_json()["designs"][0] == {"path": "square:1,cw", "n": 10}
    assert plan.has_paths
    assert plan.n_trials == 24
    assert plan.distance_m == pytest.approx(10 * 4.0 + 10 * 4.0 + 4 * 8 * 2 * 0.5 * 0.3826834)


def test_trials_of_paths_and_designs_are_numbered_in_plan_order() -> None:
    plan = parse_plan("k=0.5,l=1,n=2;path=square:1,n=3;k=0.5,l=1,n=2", "reverse")
    square = parse_path_design("square:1")
    driven = [plan.design_of(t) for t in range(1, 8)]
    assert driven[2:5] == [square] * 3
    # the one-way trials alternate as if the closed squares were not there:
    # a square leaves the robot where it found it
    line = [d for d in driven if isinstance(d, Design)]
    assert [d.backward for d in line] == [False, True, False, True]
    assert plan.excursion_m == pytest.approx(1.0)


@pytest.mark.parametrize(
    ("text", "words"),
    [
        ("path=square:1,k=1,n=3", ["path and n only", "k"]),
        ("path=square:1", ["missing n"]),
        ("path=triangle:1,n=3", ["unknown path", "square:SIDE"]),
        ("path=square:-1,n=3", ["SIDE", "positive"]),
        ("path=square:1,n=3,path=square:2", ["path is given twice"]),
    ],
)
def test_a_bad_path_design_is_refused_with_its_reason(text: str, words: list[str]) -> None:
    with pytest.raises(ParameterError) as caught:
        parse_plan(text)
    for word in words:
        assert word in str(caught.value)
    assert "plan design 1" in str(caught.value)


def test_a_closed_path_needs_its_bounding_box_of_floor() -> None:
    square = parse_path_design("square:1.5,cw")
    assert path_floor_m(square) == pytest.approx((1.5, 1.5))
    toml = (ROBOTS / "nomad150.toml").read_text(encoding="utf-8")
    small = parse_description(toml + "\n[floor]\nlength_m = 1.2\n", "robot")
    with pytest.raises(ParameterError) as caught:
        check_floor(Plan.of([(square, 10)]), small)
    assert "closed path" in str(caught.value)
    assert "1.5 m x 1.5 m box" in str(caught.value)
    roomy = parse_description(toml + "\n[floor]\nlength_m = 2\n", "robot")
    check_floor(Plan.of([(square, 10), (Design(0.5, 1.9, "reverse"), 10)]), roomy)


def _anywhere(start: StartPose) -> None:
    """Each trial starts where the robot stands (a new in-process fake)."""


BACKENDS = {
    "nomad150": "fakerobot://?seed=3&time_scale=2000",
    "create2": "fakecreate2://?seed=3&time_scale=10&max_gap_ms=15&skip_waits=1",
}


@pytest.mark.parametrize("backend", list(BACKENDS))
def test_a_session_of_squares_is_driven_journaled_and_estimated(
    tmp_path: Path, backend: str
) -> None:
    spec = SessionSpec(
        tmp_path / "session",
        robot_path=ROBOTS / f"{backend}.toml",
        plan="path=square:0.5,cw,n=4;path=square:0.5,ccw,n=4",
        measure="fake",
        port=BACKENDS[backend],
        seed=1,
        allow_few_trials=True,
    )
    with open_session(require(preflight(spec))) as opened:
        outcome = run_session(opened, start_check=_anywhere)
    assert outcome.status == "finished", outcome.message
    state = load_session(spec.folder).state
    assert state.finished
    assert [t.design.label() for t in state.completed] == ["square 0.5 m cw"] * 4 + [
        "square 0.5 m ccw"
    ] * 4
    # the tape's floor marks may leave a near-zero pose change ambiguous
    kept = [t for t in state.completed if not t.ambiguous]
    trials = session_path_trials(state)
    assert [t.trial for t in trials] == [t.trial for t in kept]
    assert [(t.family, t.direction) for t in trials] == [
        ("square", "cw" if t.trial <= 4 else "ccw") for t in kept
    ]
    # every square ends about where it started, by the encoders (each leg and
    # turn within the driver's tolerance of its target)
    for trial in state.completed:
        x, y, theta = trial.encoder_end_pose
        assert abs(x) < 0.05
        assert abs(y) < 0.05
        assert abs(theta) < 0.1
    # the one recipe estimates it with the general-path estimator
    recipe = estimate_state(state)
    assert len(recipe.path_trials) == len(kept)
    assert recipe.ambiguous == tuple(t.trial for t in state.completed if t.ambiguous)
    assert [t.trial for t in outcome.estimate.path_trials] == [t.trial for t in trials]
    assert outcome.estimate.status == recipe.status
    if recipe.result is not None:
        names = [p.name for p in recipe.result.parameters]
        assert ("e_turn" in " ".join(names)) == (backend == "create2")


def test_a_closed_paths_end_distance_is_not_judged_for_scale() -> None:
    """The finding: a 1 m square on the fake Create 2 ended 0.068 m from its
    start by the encoders (each turn within its tolerance) and 0.013 m by the
    truth; both are noise around the start, and the trial was refused as
    implausible ("displacement 0.013 m where the encoders say 0.068 m")."""
    sd = 0.03
    predicted = PosePrior(mean=np.array([0.05, -0.04, 0.03]), cov=np.diag([sd**2, sd**2, 0.04**2]))
    measured = MeasuredPose(
        pose=(0.010, -0.008, 0.02),
        covariance=((1e-6, 0.0, 0.0), (0.0, 1e-6, 0.0), (0.0, 0.0, 1e-6)),
    )
    encoders = (0.055, -0.042, 0.03)
    refused = judge(7, measured, predicted, encoders)
    assert "implausible" in refused.refusal
    assert "displacement 0.013 m where the encoders say 0.069 m" in refused.refusal
    kept = judge(7, measured, predicted, encoders, closed=True)
    assert kept.refusal == ""
    assert kept.measured.details["check"]["displacement_m"] == pytest.approx(0.0128, abs=1e-4)
