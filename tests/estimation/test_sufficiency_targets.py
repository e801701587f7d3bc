"""The sufficiency check's targets (odohil/science/targets.py): E_T relative to its size."""

from __future__ import annotations

import warnings

from odohil.science.estimators.checks import sufficiency
from odohil.science.estimators.result import ParameterEstimate
from odohil.science.parameters import NOMAD150, PARAMETER_NAMES, ErrorParameters
from odohil.science.targets import TARGET_FLOORS, default_targets


def _check(e_t: float, e_t_stderr: float) -> tuple[str, ...]:
    params = ErrorParameters(NOMAD150.e_r, e_t, NOMAD150.k_theta, NOMAD150.k_rho)
    tight = (1e-5, e_t_stderr, 1e-7, 1e-6)  # E_R, K_theta, K_rho well known
    estimates = [
        ParameterEstimate.build(name, value, se)
        for name, value, se in zip(PARAMETER_NAMES, params.as_tuple(), tight, strict=True)
    ]
    return sufficiency(estimates, params, []).unidentified


def test_e_t_known_only_to_its_own_size_is_not_enough() -> None:
    """Issue 11: a fixed +-0.05 target let E_T -0.017 +- 0.015 count as enough."""
    assert _check(-0.017, 0.015) == ("E_T",)
    assert _check(-0.017, 0.004) == ()  # 25 % of 0.017 is 0.00425


def test_e_t_near_zero_is_judged_against_the_floor() -> None:
    assert _check(0.0005, 0.0019) == ()
    assert _check(0.0005, 0.0025) == ("E_T",)


def test_default_targets_are_fractions_of_the_values_with_floors() -> None:
    targets = default_targets(NOMAD150)
    assert targets["E_R"] == abs(NOMAD150.e_r) / 4
    assert targets["E_T"] == abs(NOMAD150.e_t) / 4
    assert targets["K_theta"] == NOMAD150.k_theta / 2
    assert targets["K_rho"] == NOMAD150.k_rho / 2
    assert default_targets(ErrorParameters(0.0, 0.0, 0.0, 0.0)) == TARGET_FLOORS


def test_an_estimate_of_exactly_zero_is_judged_by_its_standard_error_without_a_warning() -> None:
    """Issue 17: a frozen motion-capture stream made E_R exactly 0 and the
    reason divided by |E_R| (``RuntimeWarning: divide by zero`` on stderr)."""
    params = ErrorParameters(0.0, NOMAD150.e_t, NOMAD150.k_theta, NOMAD150.k_rho)
    stderrs = (1e-3, 1e-5, 1e-7, 1e-6)  # E_R far above its floor
    estimates = [
        ParameterEstimate.build(name, value, se)
        for name, value, se in zip(PARAMETER_NAMES, params.as_tuple(), stderrs, strict=True)
    ]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        result = sufficiency(estimates, params, [])
    assert result.unidentified == ("E_R",)
    reason = next(r for r in result.reasons if r.startswith("E_R"))
    assert reason == (
        f"E_R has standard error 0.001 (target {TARGET_FLOORS['E_R']:.2g}); "
        "its estimate is 0, so no relative error"
    )
