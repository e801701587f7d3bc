"""The misfit checks (odohil/science/estimators/misfit.py): group biases, the
spread between groups and the trial order.

The statistics are checked against exact draws of their null (a linear model:
residuals N(0, V_i) plus a shared parameter error, fitted by generalised least
squares or held out), and end to end: a differential drive whose spins carry a
turn-scale error, calibrated with forth-and-back ``turn`` trials driven both
ways, is not trusted, and the reason names the group, the axis and the bias;
clean data stay trusted; a first trial of every run that carries a bias is
named.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from odohil.errors import ParameterError
from odohil.protocol.create2.geometry import CREATE2_GEOMETRY
from odohil.science.diff_drive import DiffDriveErrors, simulate_diff_drive
from odohil.science.estimators import Observation, estimate
from odohil.science.estimators.misfit import (
    MISFIT_LEVEL,
    TrialLabel,
    holm,
    labels_of,
    misfit_check,
    path_misfit,
)
from odohil.science.moments import pose_moments
from odohil.science.parameters import ErrorParameters
from odohil.science.path_trials import PathTrial
from odohil.science.paths import Design, EncoderPath, Turn, square
from odohil.science.simulator import simulate
from odohil.science.validation import predict_path

TRUTH = ErrorParameters.from_paper_units(-0.5, -0.02, 0.1, 1e-4)
MEASUREMENT_COV = np.diag([1e-6, 1e-6, 4e-6])
"""Tape-like: 1 mm in x and y, 2 mrad in heading."""
DESIGNS = (
    Design(1, 3.0, "turn"),
    Design(1, 3.0, "turn", backward=True),
    Design(10, 0.5, "turn"),
    Design(10, 0.5, "turn", backward=True),
)
N_PER_DESIGN = 12


def _labels() -> list[TrialLabel]:
    """4 families x 2 directions x 6 trials, in driving order."""
    out = []
    for family in ("square", "circle"):
        for direction in ("cw", "ccw"):
            out += [TrialLabel(family, direction, turns=True)] * 6
    return out


def _null_sets(
    n_sets: int, fitted: bool, seed: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Residuals of a linear model y_i = J_i b + e_i, e_i ~ N(0, V_i), b of 2
    parameters: fitted by generalised least squares on the same trials
    (``fitted``) or known with covariance Sigma and held out."""
    rng = np.random.default_rng(seed)
    n = len(_labels())
    sd = rng.uniform(0.5, 2.0, size=(n, 3)) * np.array([1e-3, 2e-3, 1e-2])
    covs = np.stack([np.diag(s**2) for s in sd])
    # a shared mean (E_R moves every heading alike) and a spread
    jac = rng.normal(1.0, 0.5, size=(n, 3, 2)) * np.array([1e-3, 2e-3, 1e-2])[None, :, None]
    info = np.einsum("nia,ni,nib->ab", jac, 1.0 / sd**2, jac)
    sigma = np.linalg.inv(info)
    out = np.empty((n_sets, n, 3))
    for k in range(n_sets):
        e = rng.normal(size=(n, 3)) * sd
        if fitted:
            score = np.einsum("nia,ni->a", jac, e / sd**2)
            out[k] = e - np.einsum("nia,a->ni", jac, sigma @ score)
        else:
            shared = rng.multivariate_normal(np.zeros(2), sigma)
            out[k] = e + np.einsum("nia,a->ni", jac, shared)
    return out, covs, jac, sigma


@pytest.mark.parametrize("fitted", [True, False])
def test_clean_residuals_fail_at_most_at_the_level(fitted: bool) -> None:
    """400 exact null sets: every group z is N(0, 1) (the parameter term of
    the right sign makes it so) and the family fails at most at its level."""
    residuals, covs, jac, sigma = _null_sets(400, fitted, seed=11 if fitted else 12)
    labels = _labels()
    failures = 0
    z_all: dict[str, list[float]] = {}
    for r in residuals:
        check = misfit_check(r, covs, labels, jac, sigma, fitted=fitted)
        failures += not check.passed
        for t in check.tests:
            if t.kind == "group":
                z_all.setdefault(f"{t.group} {t.axis}", []).append(t.statistic)
    # family-wise level 0.01: SE of the rate at 400 sets is 0.005
    assert failures / len(residuals) <= MISFIT_LEVEL + 4 * math.sqrt(0.01 * 0.99 / 400)
    for name, zs in z_all.items():
        spread = float(np.std(zs))
        assert 0.88 < spread < 1.12, f"{name}: SD of z {spread:.3f}"


def test_the_wrong_sign_of_the_parameter_term_is_seen() -> None:
    """Held-out residuals judged as fitted (the parameter term subtracted)
    have z spreads well above 1: the test above can fail."""
    residuals, covs, jac, sigma = _null_sets(200, fitted=False, seed=13)
    labels = _labels()
    zs = [
        t.statistic
        for r in residuals
        for t in misfit_check(r, covs, labels, jac, sigma, fitted=True).tests
        if t.kind == "group" and t.group == "all" and t.axis == "theta"
    ]
    assert float(np.std(zs)) > 1.15


def test_a_bias_the_variance_absorbs_is_seen_by_the_spread_test() -> None:
    """+b on cw and -b on ccw trials with the predicted variance inflated to
    b^2 + sd^2 (what a fitted K_theta does): the group z stays modest, the
    analysis of variance between the groups rejects and names the axis."""
    rng = np.random.default_rng(5)
    labels = _labels()
    n = len(labels)
    sd = 0.01
    bias = 2 * sd
    signs = np.array([1.0 if label.direction == "cw" else -1.0 for label in labels])
    r = np.zeros((n, 3))
    r[:, :2] = rng.normal(size=(n, 2)) * 1e-3
    r[:, 2] = bias * signs + rng.normal(size=n) * sd
    covs = np.broadcast_to(np.diag([1e-6, 1e-6, bias**2 + sd**2]), (n, 3, 3)).copy()
    check = misfit_check(r, covs, labels, turn_hint="calibrate with turns_exact = false")
    assert not check.passed
    spread = [t for t in check.failed() if t.kind == "spread"]
    assert spread
    assert spread[0].axis == "theta"
    reason = " ".join(check.reasons())
    assert "heading" in reason
    assert "turns_exact = false" in reason
    assert "cw" in reason


def test_holm_steps_down() -> None:
    rejected, levels = holm([0.001, 0.03, 0.012, 0.5], 0.05)
    # sorted: 0.001 <= 0.05/4, 0.012 <= 0.05/3, 0.03 > 0.05/2 stops
    assert rejected == [True, False, True, False]
    assert levels == pytest.approx([0.0125, 0.025, 0.05 / 3, 0.05])


def test_bad_shapes_are_refused() -> None:
    with pytest.raises(ParameterError, match="residuals"):
        misfit_check(np.zeros((3, 3)), np.zeros((3, 3, 3)), _labels())
    labels = _labels()[:2]
    with pytest.raises(ParameterError, match="level"):
        misfit_check(np.zeros((2, 3)), np.ones((2, 3, 3)), labels, level=0.7)


def _observations(
    rng: np.random.Generator, turn_scale: float, first_offset: float = 0.0
) -> list[Observation]:
    """12 trials of each design; ``first_offset``: heading added to each
    design's first trial (in the sense of travel), in its predicted heading
    standard deviations."""
    errors = DiffDriveErrors.from_parameters(
        TRUTH, turn_scale=turn_scale, wheel_base_m=CREATE2_GEOMETRY.wheel_base_m
    )
    out = []
    for design in DESIGNS:
        poses = simulate_diff_drive(design.path(), errors, N_PER_DESIGN, seed=rng).pose_change
        poses = poses + rng.multivariate_normal(np.zeros(3), MEASUREMENT_COV, size=N_PER_DESIGN)
        sd = math.sqrt(pose_moments(design.path(), TRUTH).cov[2, 2] + MEASUREMENT_COV[2, 2])
        # in the sense of travel: a backward trial's heading is the mirror image
        poses[0, 2] += first_offset * sd * (-1.0 if design.backward else 1.0)
        out += [Observation(design, p, MEASUREMENT_COV) for p in poses]
    return out


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_spin_error_makes_the_estimate_doubtful_and_names_the_group(seed: int) -> None:
    """A turn-scale error of 0.2 % on the spins of forth-and-back ``turn``
    trials driven both ways: the four-parameter fit absorbs it (the global
    goodness-of-fit test passes); the misfit check names the axis, the group
    and the bias in degrees, and advises turns_exact = false."""
    result = estimate(_observations(np.random.default_rng(seed), 0.002))
    assert result.model_check.p_value > 0.01  # the global test is blind to it
    assert result.verdict.status == "doubtful"
    reasons = " ".join(result.verdict.reasons)
    assert "heading residual" in reasons
    assert " deg on the " in reasons
    assert "k=10 l=0.5 m turn" in reasons
    assert "turns_exact = false" in reasons
    assert result.misfit is not None
    assert not result.misfit.passed
    assert result.to_json_dict()["misfit"]["failed"]


def test_clean_forth_and_back_data_stay_trusted() -> None:
    """No turn error: 8 data sets of 48 trials are all trusted (the check's
    family-wise level is 1 %; 8 false alarms in a row would need a broken test)."""
    rng = np.random.default_rng(21)
    statuses = [estimate(_observations(rng, 0.0)).verdict.status for _ in range(8)]
    assert statuses.count("trusted") >= 7


def test_a_biased_first_trial_of_each_run_is_named() -> None:
    """Every design's first trial (of 4 runs) carries +4 heading SDs: the
    trial-order check names it (the outlier test may name one of them too:
    the heading alone moved is off the model's heading-position correlation)."""
    rng = np.random.default_rng(8)
    result = estimate(_observations(rng, 0.0, first_offset=4.0), method="joint")
    assert result.verdict.status == "doubtful"
    assert any("first trial of each of 4 runs" in r for r in result.verdict.reasons)


def test_residuals_of_backward_trials_are_in_their_own_frame() -> None:
    """A one-way design driven both ways, a heading offset added to what is
    measured on the backward trials: E_R takes half of it, and the backward
    trials' bias is reported with the sign that was added."""
    rng = np.random.default_rng(4)
    obs = []
    for design in (Design(0.5, 3.0, "reverse"), Design(0.5, 3.0, "reverse", backward=True)):
        poses = simulate(design.path(), TRUTH, 12, seed=rng).pose_change
        if design.backward:
            poses[:, 2] += 0.03
        obs += [Observation(design, p, MEASUREMENT_COV) for p in poses]
    result = estimate(obs, method="joint")
    assert result.misfit is not None
    tests = [
        t
        for t in result.misfit.tests
        if t.kind == "group" and t.axis == "theta" and "backward" in t.group
    ]
    assert tests
    assert tests[0].bias > 0


def _path_trials(turn_scale: float, rng: np.random.Generator) -> list[PathTrial]:
    """Squares of 1 m both ways, 10 each, the robot's turns scaled by 1 + turn_scale;
    each trial in its own file, one folder per direction (a session each)."""
    trials = []
    for ccw in (False, True):
        nominal = square(1.0, counter_clockwise=ccw)
        steps = tuple(
            Turn(s.angle_rad * (1 + turn_scale)) if isinstance(s, Turn) else s
            for s in nominal.steps
        )
        poses = simulate(EncoderPath(steps), TRUTH, 10, seed=rng).pose_change
        poses = poses + rng.multivariate_normal(np.zeros(3), MEASUREMENT_COV, size=10)
        direction = "ccw" if ccw else "cw"
        trials += [
            PathTrial(
                nominal,
                p,
                MEASUREMENT_COV,
                source=f"logs/{direction}/run-{k:02d}.csv",
                family="square",
                direction=direction,
            )
            for k, p in enumerate(poses)
        ]
    return trials


def test_labels_of_general_paths_take_the_session_from_the_folder() -> None:
    trials = _path_trials(0.0, np.random.default_rng(3))
    labels = labels_of(trials)
    assert {label.cell for label in labels} == {"cw square", "ccw square"}
    assert {label.run for label in labels} == {"logs/cw", "logs/ccw"}
    assert all(label.turns for label in labels)


def test_held_out_general_paths_with_a_turn_error_are_named_by_direction() -> None:
    """Squares with a 1 % turn-scale error tested against the exact-turn
    model's prediction at the truth: the heading bias is named with its
    direction; without the error the check passes (it fails 0.7 % of clean
    sets like this one, measured over 300 seeds: the level is 1 %)."""
    predictions = [predict_path(square(1.0, ccw), TRUTH) for ccw in (False, True)]
    per_trial = [predictions[0]] * 10 + [predictions[1]] * 10
    hint = "calibrate with turns_exact = false"
    clean = path_misfit(_path_trials(0.0, np.random.default_rng(6)), per_trial, None, fitted=False)
    assert clean.passed
    biased = path_misfit(
        _path_trials(0.01, np.random.default_rng(6)), per_trial, None, fitted=False, turn_hint=hint
    )
    assert not biased.passed
    reasons = " ".join(biased.reasons())
    assert "heading residual" in reasons
    assert "cw square trials" in reasons
    assert hint in reasons
