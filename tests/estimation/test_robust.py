"""The robust default estimator, the Cox-Reid adjustment, exclusion and the verdict."""

from __future__ import annotations

import math

import numpy as np
import pytest

from odohil.errors import MeasurementError
from odohil.science.estimators import Observation, estimate
from odohil.science.estimators.estimate import joint_start
from odohil.science.estimators.joint import joint_estimate
from odohil.science.estimators.observations import group_trials, summarise
from odohil.science.estimators.paper import paper_estimate
from odohil.science.parameters import NOMAD150, PARAMETER_NAMES
from odohil.science.paths import Design
from odohil.science.simulator import simulate

A = Design(1, 6.0)
B = Design(20, 0.5)
TRUTH = NOMAD150.as_tuple()


def exact(n: int, rng: np.random.Generator) -> list[Observation]:
    """n trials of each paper design with exact poses, numbered from 1."""
    out = []
    for design in (A, B):
        for pose in simulate(design.path(), NOMAD150, n, seed=rng, segment_m=0.05).pose_change:
            out.append(Observation(design, pose, trial=len(out) + 1))
    return out


def slipped(seed: int) -> list[Observation]:
    """30 + 30 exact trials; trial 45 (design B) with 5 cm on its y."""
    obs = exact(30, np.random.default_rng(seed))
    bad = obs[44]
    obs[44] = Observation(B, bad.pose_change + np.array([0.0, 0.05, 0.0]), trial=45)
    return obs


@pytest.mark.parametrize("seed", [3, 4])
def test_one_gross_error_neither_drags_the_estimate_nor_hides(seed: int) -> None:
    obs = slipped(seed)
    gaussian = estimate(obs, "joint").parameter("K_theta")
    assert abs(gaussian.value - TRUTH[2]) > 4 * gaussian.stderr  # the failure issue 8 measured
    result = estimate(obs)
    assert result.method == "robust"
    for p, true in zip(result.parameters, TRUTH, strict=True):
        assert p.ci95[0] <= true <= p.ci95[1], p.name
    assert [(o.number, o.design) for o in result.model_check.outliers] == [
        (45, "k=20 l=0.5 m turn")
    ]
    assert result.verdict.status == "doubtful"
    assert "trial 45 (k=20 l=0.5 m turn)" in result.verdict.reasons[0]
    # the Gaussian fit is reported beside, and the trial's influence stands out
    assert [p.name for p in result.gaussian] == list(PARAMETER_NAMES)
    weights = {t.trial: t.clean_probability for t in result.trials}
    assert weights[45] < 0.01
    assert min(v for t, v in weights.items() if t != 45) > 0.5


def test_influence_predicts_leaving_the_trial_out() -> None:
    obs = exact(30, np.random.default_rng(8))
    bad = obs[40]
    obs[40] = Observation(B, bad.pose_change + np.array([0.0, 0.004, 0.0]), trial=41)
    result = estimate(obs)
    for index in (2, 0):  # K_theta, E_R
        top = max(result.trials, key=lambda t: abs(t.influence[index]))
        assert abs(top.influence[index]) > 0.3
        without = estimate(obs, exclude={top.trial})
        stderr = result.parameters[index].stderr
        moved = (without.params.as_tuple()[index] - result.params.as_tuple()[index]) / stderr
        assert moved == pytest.approx(top.influence[index], rel=0.3, abs=0.05)


def test_clean_data_are_trusted_and_the_robust_fit_is_the_gaussian_one() -> None:
    obs = exact(30, np.random.default_rng(9))
    robust = estimate(obs)
    joint = estimate(obs, "joint")
    assert robust.verdict.status == "trusted"
    assert robust.verdict.reasons == ()
    for r, j in zip(robust.parameters, joint.parameters, strict=True):
        assert abs(r.value - j.value) < 0.05 * j.stderr, r.name


def test_exclusion_is_a_view_by_trial_number() -> None:
    obs = slipped(3)
    result = estimate(obs, exclude={45})
    assert result.excluded == (45,)
    assert result.n_trials == 59
    assert result.verdict.status == "trusted"
    assert 45 not in {t.trial for t in result.trials}
    assert len(obs) == 60
    with pytest.raises(MeasurementError, match=r"no trial numbered 61 .*1\.\.60"):
        estimate(obs, exclude={61})


def test_identical_rows_fail() -> None:
    """Issue 8: 60 identical rows printed DID NOT CONVERGE beside 'enough trials', exit 0."""
    obs = [Observation(A, np.array([0.01, 0.1, -0.04]))] * 30
    obs += [Observation(B, np.array([0.002, 0.01, -0.07]))] * 30
    for method in ("robust", "joint", "paper"):
        result = estimate(obs, method)
        assert result.verdict.status == "failed", method
        assert any("degenerate" in r for r in result.verdict.reasons)
        assert result.to_json_dict()["verdict"]["status"] == "failed"


def test_many_ambiguous_trials_left_out_make_the_verdict_doubtful() -> None:
    result = estimate(exact(10, np.random.default_rng(10)), ambiguous=[4, 17, 21])
    assert result.verdict.status == "doubtful"
    assert "ambiguous" in result.verdict.reasons[0]
    assert "4, 17, 21" in result.verdict.reasons[0]


def test_a_few_ambiguous_trials_left_out_are_listed_but_leave_the_verdict_trusted() -> None:
    """Issue 8: with one cross distance, 11 % of clean sessions were called
    doubtful only because a trial or two was ambiguous. Leaving up to 10 % of
    the trials out keeps the estimate right within its uncertainty
    (bench/operator_faults.py, BENCHMARKS.md); they are listed in the notes."""
    result = estimate(exact(10, np.random.default_rng(10)), ambiguous=[4, 17])
    assert result.verdict.status == "trusted"
    assert any("ambiguous" in n and "4, 17" in n for n in result.notes)


def test_paper_method_is_checked_at_the_maximum_likelihood_fit() -> None:
    obs = exact(30, np.random.default_rng(11))
    paper = estimate(obs, "paper")
    joint = estimate(obs, "joint")
    assert paper.params != joint.params
    assert paper.model_check.chi2 == pytest.approx(joint.model_check.chi2, rel=1e-9)


@pytest.mark.slow
def test_cox_reid_removes_most_of_the_small_sample_bias_of_k_theta() -> None:
    """n = 5 per design, exact poses: the plain ML K_theta is biased low
    (issue 8 measured -10.9 %); the adjusted one much less."""
    rng = np.random.default_rng(12)
    plain, adjusted = [], []
    for _ in range(100):
        groups = group_trials(exact(5, rng))
        start = joint_start(paper_estimate(summarise(groups)))
        plain.append(math.log(joint_estimate(groups, start).params.k_theta / TRUTH[2]))
        adjusted.append(
            math.log(joint_estimate(groups, start, cox_reid=True).params.k_theta / TRUTH[2])
        )
    # median log ratio: robust to the skew of a variance estimate at n = 5
    assert np.median(plain) < -0.05
    assert abs(np.median(adjusted)) < abs(np.median(plain)) / 2


def test_the_live_estimate_carries_a_verdict() -> None:
    from odohil.science.estimators import IncrementalEstimator

    obs = slipped(3)
    live = IncrementalEstimator()
    for o in obs:
        live.add(o)
    data = live.result().to_json_dict()
    assert data["verdict"]["status"] == "doubtful"
    assert "trial 45" in data["verdict"]["reasons"][0]


@pytest.mark.slow
def test_coverage_smoke_at_n_10_per_design() -> None:
    """60 data sets of 10 + 10 exact trials: every 95 % interval covers the
    truth in at least 95 % - 3 binomial SE of them (at least 52 of 60; a
    method whose true coverage is 95 % passes with probability 0.997, one at
    80 % fails with probability 0.87). Full-size coverage is measured by
    bench/coverage.py (the floor-marks path) and bench/wald_vs_profile.py
    (exact poses, n = 5 per design), BENCHMARKS.md."""
    rng = np.random.default_rng(13)
    reps = 60
    hits = np.zeros(4)
    for _ in range(reps):
        result = estimate(exact(10, rng))
        for i, (p, true) in enumerate(zip(result.parameters, TRUTH, strict=True)):
            hits[i] += p.ci95[0] <= true <= p.ci95[1]
    assert np.all(hits / reps >= 0.95 - 3 * math.sqrt(0.95 * 0.05 / reps)), hits / reps
