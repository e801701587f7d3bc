"""Plans of general paths (odohil/science/path_plans.py, path_plan_search.py,
path_comparison.py and path_estimability.py; issue 19 deliverables 3 and 4):
the Fisher information with a differential drive's turn errors held to
simulations of the discrete model (the score's covariance, and the spread of
maximum-likelihood estimates over simulated data sets), what a plan can and
cannot estimate, and what squares and circles buy over forth-and-back plans."""

from __future__ import annotations

import math

import numpy as np
import pytest

from odohil.errors import ParameterError
from odohil.science.diff_drive import simulate_turn_errors
from odohil.science.estimators.paths import fit_paths, turn_model
from odohil.science.fisher import default_description, fisher_information, pose_spread_measurement
from odohil.science.moments import BATCH_COLUMNS, PathSet, TurnErrors, batch_moments
from odohil.science.parameters import NOMAD150, ErrorParameters
from odohil.science.path_comparison import compare_with_paths
from odohil.science.path_designs import parse_path_design
from odohil.science.path_estimability import plan_estimability
from odohil.science.path_plans import (
    RobotModel,
    Shape,
    acting,
    path_informations,
    plan_information,
    score_plan,
    shape_label,
    shape_path,
)
from odohil.science.path_trials import PathTrial
from odohil.science.paths import Design, EncoderPath, Leg, Turn, square
from odohil.units import wrap_angles

CREATE2_LIKE = ErrorParameters.from_paper_units(-0.35, -0.015, 0.02, 5e-5)
TURNS = TurnErrors.uniform(0.012, 2e-4)
TAPE = default_description(0.001)


def arc_circle(radius_m: float, n_legs: int, ccw: bool) -> EncoderPath:
    """A circle cut into short legs, its heading changes arc turns (a
    differential drive following an arc)."""
    angle = 2 * math.pi / n_legs * (1 if ccw else -1)
    chord = 2 * radius_m * math.sin(abs(angle) / 2)
    steps: list[Leg | Turn] = [Turn(angle / 2, "arc")]
    for i in range(n_legs):
        steps += [Leg(chord), Turn(angle if i < n_legs - 1 else angle / 2, "arc")]
    return EncoderPath(tuple(steps), name=f"arc circle r={radius_m:g} m {'ccw' if ccw else 'cw'}")


def robot(*, split: bool = False, exact: bool = False) -> RobotModel:
    return RobotModel(
        CREATE2_LIKE, turns_exact=exact, turns=TURNS, split_directions=split, description=TAPE
    )


# --- the information ---------------------------------------------------------------


def test_designs_of_a_robot_whose_turns_are_exact_get_the_planners_information() -> None:
    plan = [(Design(1, 6.0, "turn"), 30), (Design(20, 0.5, "turn"), 30)]
    ours = plan_information(plan, RobotModel(NOMAD150, description=TAPE))
    theirs = fisher_information(plan, NOMAD150, pose_spread_measurement(TAPE, NOMAD150))
    scale = np.sqrt(np.outer(np.diag(theirs), np.diag(theirs)))
    assert np.max(np.abs(ours - theirs) / scale) < 1e-5


def test_turn_errors_do_not_act_on_turn_free_trials() -> None:
    plan: list[tuple[Shape, int]] = [
        (Design(0.5, 2.0, "reverse"), 20),
        (Design(5, 0.5, "reverse"), 20),
    ]
    score = score_plan(plan, robot())
    assert score.not_estimable == ("e_turn_spin", "e_turn_arc", "K_spin")
    assert "makes no spins" in score.parameter("e_turn_spin").reason
    assert "makes no arcs" in score.parameter("e_turn_arc").reason
    four = score_plan(plan, robot(exact=True))
    np.testing.assert_allclose(score.standard_errors[:4], four.standard_errors, rtol=1e-9)


@pytest.mark.parametrize("split", [False, True])
@pytest.mark.parametrize(
    "shapes",
    [
        [square(1.0, True), square(1.0, False), Design(0.5, 2.0, "reverse")],
        [Design(1, 2.0, "turn"), Design(0.5, 2.0, "reverse")],
        [arc_circle(0.5, 12, True), square(1.0, False), Design(0.5, 2.0, "reverse")],
        [Design(0.5, 2.0, "reverse")],
    ],
)
def test_the_turn_errors_that_act_are_those_the_estimator_fits(
    shapes: list[Shape], split: bool
) -> None:
    """odohil/science/estimators/paths.py fits an e_turn for every kind (and
    direction) of turn the trials make and K_spin when they spin: exactly the
    turn errors the plan's statement finds acting."""
    model = robot(split=split)
    paths = [shape_path(s) for s in shapes]
    idle = acting(paths, model)
    groups = dict(model.turn_groups)
    ours = {groups[name] for name in groups if name not in idle}
    fitted = turn_model(paths, split_directions=split)
    assert {members for _, members in fitted.classes} == ours
    assert fitted.k_spin == ("K_spin" not in idle)


def _scores(path: EncoderPath, model: RobotModel, poses: np.ndarray) -> np.ndarray:
    """Each pose's score (n, p) under the Gaussian model, its derivatives by
    plain central differences of batch_moments (independent of the module's)."""
    base = model.row()
    rows = [base]
    steps = []
    for cols in model.columns():
        step = 1e-5 * max(abs(float(base[cols[0]])), 1e-4)
        for offset in (step, -step):
            row = base.copy()
            row[cols] += offset
            rows.append(row)
        steps.append(step)
    means, covs = batch_moments(PathSet.of((path,)), np.array(rows))
    meas = np.asarray(model.measurement_cov)
    total = covs[0, 0] + meas
    inverse = np.linalg.inv(total)
    resid = poses - means[0, 0]
    resid[:, 2] = wrap_angles(resid[:, 2])
    out = np.empty((len(poses), len(steps)))
    for a, step in enumerate(steps):
        d_mean = (means[1 + 2 * a, 0] - means[2 + 2 * a, 0]) / (2 * step)
        d_cov = (covs[1 + 2 * a, 0] - covs[2 + 2 * a, 0]) / (2 * step)
        quad = inverse @ d_cov @ inverse
        out[:, a] = resid @ inverse @ d_mean + 0.5 * (
            np.einsum("ni,ij,nj->n", resid, quad, resid) - np.trace(inverse @ d_cov)
        )
    return out


MOCAP = np.diag([2.5e-7, 2.5e-7, 2.5e-7])
"""Motion capture: 0.5 mm and 0.5 mrad on a pose change."""
TRUTH = ErrorParameters.from_paper_units(-0.35, -0.015, 0.1, 1e-4)


@pytest.mark.parametrize(
    "path",
    [square(1.0, False), arc_circle(0.5, 12, True), Design(2, 1.0, "turn").path()],
    ids=["square cw", "arc circle", "forth-and-back turns"],
)
def test_one_trials_information_is_its_scores_covariance_in_simulations(
    path: EncoderPath,
) -> None:
    """The information of one trial of a general path with turn errors equals
    the covariance of the Gaussian score over trials simulated with the
    discrete model (odohil/science/diff_drive.py simulate_turn_errors), each
    diagonal entry within 4 Monte Carlo standard errors (4th moments of the
    sampled scores)."""
    model = RobotModel(TRUTH, turns_exact=False, turns=TURNS, measurement_cov=MOCAP)
    rng = np.random.default_rng(20261127)
    n = 20000
    poses = simulate_turn_errors(path, TRUTH, TURNS, n, seed=rng).pose_change
    poses += rng.multivariate_normal(np.zeros(3), MOCAP, n)
    scores = _scores(path, model, poses)
    info = path_informations([path], model)[0]
    live = np.diag(info) > 0
    empirical = (scores**2).mean(axis=0)
    mc_se = np.sqrt(((scores**2 - empirical) ** 2).mean(axis=0) / n)
    z = (empirical - np.diag(info))[live] / mc_se[live]
    assert np.all(np.abs(z) < 4.0), (model.names, z)
    assert np.all(np.abs(scores.mean(axis=0)[live]) < 4.0 * scores.std(axis=0)[live] / math.sqrt(n))


def test_expected_standard_errors_are_the_spread_of_ml_estimates() -> None:
    """Cramer-Rao standard errors of a plan of squares both ways, arc circles
    both ways and one-way runs (all seven parameters of the turn-error model)
    against the spread of the maximum-likelihood fit
    (odohil/science/estimators/paths.py fit_paths) over 80 data sets simulated
    with the discrete model: each within 4 Monte Carlo standard errors of the
    spread (from the estimates' 4th moments). bench/path_plans_mc.py runs
    more data sets (BENCHMARKS.md)."""
    model = RobotModel(TRUTH, turns_exact=False, turns=TURNS, measurement_cov=MOCAP)
    plan: list[tuple[Shape, int]] = [
        (square(1.0, True), 10),
        (square(1.0, False), 10),
        (Design(0.5, 2.0, "reverse"), 10),
        (arc_circle(0.5, 12, True), 10),
        (arc_circle(0.5, 12, False), 10),
    ]
    expected = score_plan(plan, model)
    assert expected.not_estimable == ()
    rng = np.random.default_rng(7)
    sets = 80
    estimates = []
    for _ in range(sets):
        trials = []
        for shape, n in plan:
            path = shape_path(shape)
            poses = simulate_turn_errors(path, TRUTH, TURNS, n, seed=rng).pose_change
            poses += rng.multivariate_normal(np.zeros(3), MOCAP, n)
            trials += [PathTrial(path, pose, MOCAP) for pose in poses]
        fit = fit_paths(trials, turns_exact=False)
        assert fit.point.layout.names == expected.names
        estimates.append(fit.values)
    values = np.array(estimates)
    spread = values.std(axis=0, ddof=1)
    deviations = values - values.mean(axis=0)
    fourth = (deviations**4).mean(axis=0)
    mc_se = np.sqrt((fourth - spread**4) / sets) / (2 * spread**2)  # of spread / spread
    z = (spread / expected.standard_errors - 1.0) / mc_se
    assert np.all(np.abs(z) < 4.0), dict(zip(expected.names, z.round(2), strict=True))
    bias = (values.mean(axis=0) - model.values()) / (spread / math.sqrt(sets))
    assert np.all(np.abs(bias) < 4.0), dict(zip(expected.names, bias.round(2), strict=True))


# --- what a plan can estimate --------------------------------------------------------


def test_one_turn_design_confounds_e_turn_with_E_R_two_leg_lengths_separate_them() -> None:
    """A forth-and-back trial's heading drifts E_R 2kl + e_turn 2k pi: one leg
    length cannot tell the two apart (only the positions do, barely), two can."""
    one = score_plan([(Design(1, 2.0, "turn"), 30)], robot())
    a, b = one.names.index("E_R"), one.names.index("e_turn_spin")
    assert one.correlation[a, b] < -0.99
    assert "nearly confounded with e_turn_spin" in one.parameter("E_R").note
    two = score_plan([(Design(1, 4.0, "turn"), 20), (Design(10, 0.5, "turn"), 20)], robot())
    assert abs(two.correlation[a, b]) < 0.9
    assert two.parameter("E_R").standard_error < one.parameter("E_R").standard_error / 10


def test_squares_of_one_sense_confound_e_turn_with_E_R() -> None:
    ccw = plan_estimability([(square(1.0, True), 20)], robot())
    assert any("E_R and e_turn_spin are nearly confounded" in note for note in ccw.notes)
    both = plan_estimability(
        [(square(1.0, True), 10), (square(1.0, False), 10), (Design(0.5, 2.0, "reverse"), 10)],
        robot(),
    )
    assert not any("E_R and e_turn_spin" in note for note in both.notes)
    assert both.ok
    assert both.estimable == ("E_R", "E_T", "K_theta", "K_rho", "e_turn_spin", "K_spin")
    assert both.not_estimable == (
        ("e_turn_arc", "the plan makes no arcs (curves), so it does not act on its trials"),
    )
    text = both.text()
    assert "the turn errors with the four (not folded into E_R and K_theta)" in text
    assert "If the data ask for one e_turn per direction, the split fit estimates" in text
    assert "e_turn_spin_cw (SE " in text
    assert "Cannot estimate e_turn_arc: the plan makes no arcs" in text


def test_a_plan_that_cannot_give_an_estimate_says_why() -> None:
    spins = EncoderPath((Turn(math.pi), Leg(1e-9), Turn(math.pi)), name="spin in place")
    statement = plan_estimability([(spins, 30)], robot())
    assert not statement.ok
    assert any(p.startswith("K_theta is not identified") for p in statement.problems)
    few = plan_estimability([(square(1.0, True), 3), (square(1.0, False), 3)], robot())
    assert few.problems == ("6 trials for 6 parameters: need at least 7",)
    with pytest.raises(ParameterError, match="n must be non-negative"):
        plan_estimability([(square(1.0, True), -1)], robot())


def test_shape_labels_name_the_sense() -> None:
    assert shape_label(square(1.0, False)) == "square 1 m cw"
    assert shape_label(Design(0.5, 2.0, "reverse")) == "k=0.5 l=2 m reverse"
    assert shape_label(arc_circle(0.5, 12, True)) == "arc circle r=0.5 m ccw"
    assert shape_label(parse_path_design("circle:0.5,16,cw")) == "circle r=0.5 m 16 sides cw"


# --- what general paths buy ------------------------------------------------------------


def test_clockwise_turn_errors_need_clockwise_paths() -> None:
    """With one e_turn per direction (a real differential drive's spins slip
    differently each way, issue 20), forth-and-back designs (all turning
    counter-clockwise) never estimate the clockwise one: squares both ways
    do, at the same operator time."""
    shapes = [square(1.0, True), square(1.0, False)]
    found = compare_with_paths(robot(split=True), shapes, 2 * 3600.0)
    assert found.turn_free is not None
    assert found.forth_and_back is not None
    assert found.with_paths is not None
    for plan in (found.turn_free, found.forth_and_back, found.with_paths):
        assert plan.seconds <= 2 * 3600.0
    assert "e_turn_spin_cw" in found.buys
    cw = {g.name: g for g in found.gains}["e_turn_spin_cw"]
    assert cw.newly_estimable
    assert math.isinf(cw.turn_free)
    assert "no clockwise spins" in found.forth_and_back.parameter("e_turn_spin_cw").reason
    assert any(
        line.startswith("e_turn_spin_cw:") and "estimable only with them" in line
        for line in found.findings
    )
    assert math.isinf({g.name: g for g in found.gains}["e_turn_spin_ccw"].turn_free)


def test_one_e_turn_for_both_ways_forth_and_back_turns_do_as_well_as_squares() -> None:
    """With one e_turn for spins both ways, forth-and-back turn designs (next
    to one-way runs) estimate it as well as squares do in the same time:
    squares buy nothing there, and the comparison says so."""
    found = compare_with_paths(robot(), [square(1.0, True), square(1.0, False)], 2 * 3600.0)
    assert found.buys == ()
    gain = {g.name: g for g in found.gains}["e_turn_spin"]
    assert math.isinf(gain.turn_free)
    assert math.isfinite(gain.forth_and_back)


def test_arc_turn_errors_need_arcs() -> None:
    found = compare_with_paths(
        robot(), [arc_circle(0.5, 12, True), arc_circle(0.5, 12, False)], 2 * 3600.0
    )
    assert "e_turn_arc" in found.buys
    assert {g.name: g for g in found.gains}["e_turn_arc"].newly_estimable


def test_batch_columns_are_the_ones_the_model_sets() -> None:
    model = robot(split=True)
    assert [BATCH_COLUMNS[c] for cols in model.columns() for c in cols] == list(BATCH_COLUMNS)
