"""Per-trial scores and the sandwich ratio (odohil/science/estimators/scores.py),
checked against Monte Carlo draws of the discrete model."""

from __future__ import annotations

import math

import numpy as np
import pytest

from odohil.science.estimators import Observation, estimate
from odohil.science.estimators.estimate import fit_joint
from odohil.science.estimators.intervals import profile_interval
from odohil.science.estimators.likelihood import to_phi
from odohil.science.estimators.observations import group_trials, summarise
from odohil.science.estimators.paper import paper_estimate
from odohil.science.estimators.scores import sandwich_ratio, trial_scores
from odohil.science.parameters import NOMAD150
from odohil.science.paths import Design
from odohil.science.simulator import simulate

A = Design(1, 6.0)
B = Design(20, 0.5)
MEASUREMENT_COV = np.diag([1.0e-6, 1.0e-6, 1.6e-5])
"""About what one cross distance leaves: 1 mm in x and y, 4 mrad in heading."""


def trials(n: int, seed: int, law: str, designs: tuple[Design, ...] = (A, B)) -> list[Observation]:
    """n trials of each design: the model's true pose change plus a
    measurement error of covariance MEASUREMENT_COV, Gaussian or (``t3``)
    Student-t with 3 degrees of freedom scaled to the same covariance."""
    rng = np.random.default_rng(seed)
    root = np.linalg.cholesky(MEASUREMENT_COV)
    out: list[Observation] = []
    for design in designs:
        poses = simulate(design.path(), NOMAD150, n, seed=rng, segment_m=0.05).pose_change
        z = rng.standard_normal((n, 3))
        if law == "t3":
            z = rng.standard_t(3, (n, 3)) / math.sqrt(3.0)
        for pose, e in zip(poses, z @ root.T, strict=True):
            out.append(Observation(design, pose + e, MEASUREMENT_COV, trial=len(out) + 1))
    return out


@pytest.mark.parametrize("design", [A, B], ids=["A", "B"])
def test_scores_have_mean_zero_and_the_information_as_covariance(design: Design) -> None:
    """4000 simulated trials at the true parameters: each score's mean is 0
    and its mean square is the expected information per trial, within 4 Monte
    Carlo SE (a wrong derivative or a missing 1/2 moves these by far more)."""
    observations = trials(4000, 7, "gauss", (design,))
    scores, information = trial_scores(observations, to_phi(NOMAD150), np.ones(len(observations)))
    n = len(observations)
    per_trial = information / n
    for k in range(4):
        g = scores[:, k]
        assert abs(g.mean()) < 4 * g.std() / math.sqrt(n), k
        square = g**2
        se = square.std() / math.sqrt(n)
        assert abs(square.mean() - per_trial[k, k]) < 4 * se, (k, square.mean(), per_trial[k, k])
    off = scores[:, 2] * scores[:, 3]
    assert abs(off.mean() - per_trial[2, 3]) < 4 * off.std() / math.sqrt(n)


def test_the_ratio_is_about_one_when_the_model_holds_and_grows_with_heavy_tails() -> None:
    """600 trials of each paper design at the truth: Gaussian measurement
    errors give a K_theta ratio near 1; Student-t(3) errors of the same
    covariance (the same data otherwise) give a clearly larger one."""
    phi = to_phi(NOMAD150)
    gauss = trials(600, 11, "gauss")
    heavy = trials(600, 11, "t3")
    ratio_gauss = sandwich_ratio(*trial_scores(gauss, phi, np.ones(len(gauss))))
    ratio_heavy = sandwich_ratio(*trial_scores(heavy, phi, np.ones(len(heavy))))
    assert 0.8 < ratio_gauss[2] < 1.25, ratio_gauss
    assert ratio_heavy[2] > 1.3 * ratio_gauss[2], (ratio_heavy, ratio_gauss)


def test_heavy_tails_widen_the_reported_k_theta_interval() -> None:
    """The estimate's K_theta interval is the profile interval with the
    threshold times the sandwich ratio: in log K, its half-widths grow by
    about the root of the ratio, and the method names it."""
    observations = trials(60, 5, "t3")
    groups = group_trials(observations)
    fit = fit_joint(groups, paper_estimate(summarise(groups)))
    ratio = sandwich_ratio(*trial_scores(observations, fit.point.phi, np.ones(len(observations))))
    assert ratio[2] > 1.2
    plain = profile_interval(groups, fit, 2)
    widened = profile_interval(groups, fit, 2, widen=float(ratio[2]))
    reported = estimate(observations, "joint").parameters[2]
    assert reported.ci95 == pytest.approx(widened.ci95, rel=1e-6)
    assert f"{ratio[2]:.2f}" in reported.interval
    centre = math.log(fit.params.k_theta)
    for end in (0, 1):
        grown = abs(math.log(widened.ci95[end]) - centre) / abs(math.log(plain.ci95[end]) - centre)
        assert grown == pytest.approx(math.sqrt(ratio[2]), rel=0.15), (end, grown)


def test_few_trials_give_no_ratio() -> None:
    observations = trials(2, 3, "gauss")
    ratio = sandwich_ratio(*trial_scores(observations, to_phi(NOMAD150), np.ones(4)))
    assert np.all(np.isnan(ratio))
