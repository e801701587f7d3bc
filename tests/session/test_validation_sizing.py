"""``validate --detect``: the trials a validation drives, sized to catch an
error with probability 0.9 (odohil/session/commands/validate_power.py, issue 31).

The calibration is a trial file of the discrete model's trials at the Nomad's
values (two designs, 20 trials each, read with the README's robot); its
estimate is what ``odohil validate`` would test. The power itself is checked
against the discrete model's Monte Carlo in tests/science/test_validation_power.py.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from odohil.errors import ParameterError
from odohil.science.estimators import EstimateResult
from odohil.science.floor_marks import pose_covariance
from odohil.science.parameters import NOMAD150
from odohil.science.paths import Design
from odohil.science.simulator import simulate
from odohil.science.validation import N_TESTS
from odohil.science.validation_power import verdict_power
from odohil.session.commands.validate_power import _truth, parse_detect, size_validation
from odohil.session.results.outcome import estimate_source
from odohil.session.results.validation import (
    parameter_covariance,
    parse_validation_path,
    predict_calibrated,
)
from odohil.session.robots.registry import parse_description
from tests.session.test_trust_runs import readme_robot

DESCRIPTION = parse_description(readme_robot(), "robot.toml")
PATH = "forth-back:2,1.5"


@pytest.fixture(scope="module")
def calibration(tmp_path_factory: pytest.TempPathFactory) -> EstimateResult:
    rows = ["k,l_m,variant,dx_m,dy_m,dtheta_rad"]
    rng = np.random.default_rng(3)
    for design in (Design(1, 3.0), Design(10, 0.5)):
        poses = simulate(design.path(), NOMAD150, 20, seed=rng, segment_m=0.01).pose_change
        poses = poses + rng.normal(0.0, [1e-3, 1e-3, 2e-3], poses.shape)
        rows += [
            f"{design.k:g},{design.l_m:g},turn,{x!r},{y!r},{t!r}" for x, y, t in poses.tolist()
        ]
    file = tmp_path_factory.mktemp("sizing") / "calibration.csv"
    file.write_text("\n".join(rows) + "\n", encoding="utf-8")
    result = estimate_source([file], DESCRIPTION).result
    assert result is not None
    return result


def test_the_errors_are_read_in_the_papers_units() -> None:
    found = parse_detect("E_R=0.4, E_T=2%, K_theta=0.1,K_rho=1e-5")
    assert [d.name for d in found] == ["E_R", "E_T", "K_theta", "K_rho"]
    assert found[0].shift == pytest.approx(math.radians(0.4))
    assert found[1].shift == pytest.approx(0.02)
    assert found[2].shift == pytest.approx(0.1 * math.radians(1) ** 2)
    assert found[3].shift == 1e-5
    assert parse_detect("E_T=-0.02")[0].shift == -0.02
    assert found[0].text() == "E_R off by 0.4 deg/m"


@pytest.mark.parametrize(
    ("text", "words"),
    [
        ("X=1", ["--detect", "NAME=VALUE", "E_R, E_T, K_theta, K_rho"]),
        ("E_R", ["--detect", "NAME=VALUE"]),
        ("E_R=abc", ["--detect E_R=abc", "not a number"]),
        ("E_R=0", ["not 0"]),
        ("E_R=nan", ["finite"]),
        ("K_theta=-0.1", ["positive", "steadier"]),
        ("K_rho=1%", ["only E_T and e_turn"]),
        ("E_R=1,E_R=2", ["E_R named twice"]),
    ],
)
def test_a_malformed_detect_is_refused_naming_the_option(text: str, words: list[str]) -> None:
    with pytest.raises(ParameterError) as caught:
        parse_detect(text)
    for word in words:
        assert word in str(caught.value)


def test_the_planned_count_is_the_fewest_that_catch_each_error(
    calibration: EstimateResult,
) -> None:
    vpath = parse_validation_path(PATH)
    sizing = size_validation(
        "E_R=0.4,K_theta=0.096", vpath, calibration, DESCRIPTION, measure="fake", trials=None,
        alpha=0.01,
    )  # fmt: skip
    assert not sizing.given
    assert sizing.trials == max(c.plan.trials or 0 for c in sizing.caught)
    assert all(c.power >= 0.9 for c in sizing.caught)
    # the spread error needs the most; one trial fewer misses 0.9
    k_theta = sizing.caught[1]
    assert k_theta.plan.trials == sizing.trials > 1
    assert k_theta.test in ("overall", "theta")
    assert vpath.path is not None
    prediction = predict_calibrated(vpath.path, calibration)
    fewer = verdict_power(
        prediction, _truth(vpath.path, calibration, k_theta.detect), sizing.trials - 1,
        measurement_cov=pose_covariance(DESCRIPTION, prediction.mean),
        parameter_cov=parameter_covariance(calibration), level=0.01 / N_TESTS,
    )  # fmt: skip
    assert fewer.power < 0.9
    lines = sizing.lines()
    assert lines[0] == f"trials: {sizing.trials} of {PATH} (planned by --detect)"
    assert lines[2].startswith("  K_theta off by 0.096 deg^2/m: caught with probability 0.9")
    assert sizing.to_json_dict()["detect"]["K_theta"]["trials"] == sizing.trials


def test_a_given_count_is_checked_not_replaced(calibration: EstimateResult) -> None:
    vpath = parse_validation_path(PATH)
    planned = size_validation(
        "K_theta=0.096", vpath, calibration, DESCRIPTION, measure=None, trials=None, alpha=0.01
    ).trials
    more = size_validation(
        "K_theta=0.096", vpath, calibration, DESCRIPTION, measure=None, trials=planned + 5,
        alpha=0.01,
    )  # fmt: skip
    assert (more.trials, more.given) == (planned + 5, True)
    assert more.caught[0].power > 0.9
    with pytest.raises(ParameterError) as caught:
        size_validation(
            "K_theta=0.096", vpath, calibration, DESCRIPTION, measure=None, trials=planned - 1,
            alpha=0.01,
        )  # fmt: skip
    message = str(caught.value)
    assert f"--trials {planned - 1} with --detect" in message
    assert f"give --trials {planned}" in message


def test_a_path_that_cannot_catch_the_error_says_so_and_what_would_help(
    calibration: EstimateResult,
) -> None:
    # E_R off by 0.002 deg/m: below the calibration's own uncertainty of E_R
    se = next(p.stderr for p in calibration.parameters if p.name == "E_R")
    assert math.degrees(se) > 0.002
    with pytest.raises(ParameterError) as caught:
        size_validation(
            "E_R=0.002", parse_validation_path(PATH), calibration, DESCRIPTION, measure=None,
            trials=None, alpha=0.01,
        )  # fmt: skip
    message = str(caught.value)
    assert "cannot catch E_R off by 0.002 deg/m with probability 0.9 in 10000 trials" in message
    assert "(best 0." in message
    for help_ in ("a longer path", "a different path", "a more precise calibration"):
        assert help_ in message


def test_the_trials_of_a_file_are_not_sized(calibration: EstimateResult, tmp_path: Path) -> None:
    with pytest.raises(ParameterError, match="--detect sizes the trials a validation drives"):
        size_validation(
            "E_R=0.4", parse_validation_path(f"file:{tmp_path / 'x.csv'}"), calibration,
            DESCRIPTION, measure=None, trials=None, alpha=0.01,
        )  # fmt: skip
