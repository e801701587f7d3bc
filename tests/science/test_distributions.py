"""odohil/science/distributions.py gives the numbers scipy.stats gives.

The package uses the few distribution functions of that module instead of
scipy.stats (whose import costs about 1 s of CPU in every process); each must
equal scipy.stats' function over a grid of points and degrees of freedom,
including the edges of the support and invalid degrees of freedom.
"""

from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pytest
from scipy import stats

from odohil.science import distributions

PROBABILITIES = (0.0, 1e-300, 1e-12, 1e-6, 0.001, 0.00625, 0.01, 0.05, 0.5, 0.9, 0.95, 0.975)
PROBABILITIES += (*(1.0 - p for p in (1e-12, 6.3e-5, 1e-6)), 1.0)
POINTS = (-3.0, -1e-9, 0.0, 1e-9, 0.01, 0.5, 1.0, 2.7, 3.0, 7.81, 30.0, 150.0, 1e4, math.inf)
DOFS = (-1.0, 0.0, 0.5, 1.0, 2.0, 3.0, 4.5, 9.0, 27.0, 300.0, 1e6, math.inf)


def _same(ours: float, theirs: object) -> None:
    expected = float(np.asarray(theirs))
    if math.isnan(expected):
        assert math.isnan(ours)
    else:
        assert ours == pytest.approx(expected, rel=1e-12, abs=1e-300)


@pytest.mark.parametrize("dof", [d for d in DOFS if math.isfinite(d)])
def test_chi2_functions_equal_scipy_stats(dof: float) -> None:
    for x in POINTS:
        _same(distributions.chi2_sf(x, dof), stats.chi2.sf(x, dof))
    each = distributions.chi2_sf_each(np.array(POINTS), dof)
    for x, value in zip(POINTS, each, strict=True):
        _same(float(value), stats.chi2.sf(x, dof))
    for p in PROBABILITIES:
        _same(distributions.chi2_isf(p, dof), stats.chi2.isf(p, dof))
        _same(distributions.chi2_ppf(p, dof), stats.chi2.ppf(p, dof))


@pytest.mark.parametrize("dof", DOFS)
def test_t_quantile_equals_scipy_stats(dof: float) -> None:
    for p in PROBABILITIES:
        _same(distributions.t_ppf(p, dof), stats.t.ppf(p, dof))


def test_normal_functions_equal_scipy_stats() -> None:
    for z in (-math.inf, -40.0, -8.0, -4.0, -1.96, 0.0, 1e-9, 1.0, 4.0, 8.0, 40.0, math.inf):
        _same(distributions.norm_cdf(z), stats.norm.cdf(z))
        _same(distributions.norm_sf(z), stats.norm.sf(z))
    for p in PROBABILITIES:
        _same(distributions.norm_isf(p), stats.norm.isf(p))


@pytest.mark.parametrize("dof_num", [-1.0, 0.0, 1.0, 2.0, 5.0, 40.0])
def test_f_survival_equals_scipy_stats(dof_num: float) -> None:
    for dof_den in (0.0, 1.0, 3.0, 10.0, 200.0):
        for x in POINTS:
            _same(distributions.f_sf(x, dof_num, dof_den), stats.f.sf(x, dof_num, dof_den))


@pytest.mark.parametrize("dof", [1.0, 3.0, 8.0])
def test_the_noncentrality_for_a_probability_is_scipy_stats_ncx2s(dof: float) -> None:
    for x in (10.83, 16.27, 40.0):  # central cdf above each cdf: an nc >= 0 reaches it
        for cdf in (0.05, 0.2, 0.5):
            nc = distributions.ncx2_noncentrality(x, dof, cdf)
            assert float(stats.ncx2.cdf(x, dof, nc)) == pytest.approx(cdf, rel=1e-9)
    assert math.isnan(distributions.ncx2_noncentrality(3.0, 0.0, 0.2))


def test_the_written_out_four_sigma_levels_are_the_normal_distributions() -> None:
    """Two modules write a 4-sigma level out (importing them computes nothing with
    scipy): exactly the values the functions give."""
    from odohil.science.estimators import intervals, result

    assert 1.0 - 2.0 * distributions.norm_sf(intervals.FOUR_SIGMA) == intervals.LEVEL_4SIGMA
    assert distributions.norm_cdf(4.0) == result._FOUR_SIGMA_UPPER


def test_importing_the_science_imports_no_scipy_special() -> None:
    """scipy.special (0.3 s of CPU at start) is imported at the first probability
    computed, not with the modules (odohil/science/distributions.py)."""
    probe = (
        "import sys\n"
        "import odohil.science.estimators, odohil.science.floor_marks\n"
        "import odohil.science.validation, odohil.science.pose_selection\n"
        "print('before', 'scipy.special' in sys.modules)\n"
        "from odohil.science import distributions\n"
        "distributions.chi2_sf(1.0, 2.0)\n"
        "print('after', 'scipy.special' in sys.modules)\n"
    )
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=60)
    assert done.stdout.split() == ["before", "False", "after", "True"], done.stderr


@pytest.mark.parametrize(
    ("weights", "dofs", "noncentralities", "x"),
    [
        ((2.0, 0.5), (3.0, 5.0), (0.0, 0.0), 10.0),
        ((2.0, 0.5), (3.0, 5.0), (4.0, 1.0), 20.0),
        ((1.0, 1.3, 0.7), (1.0, 1.0, 1.0), (2.0, 0.0, 1.0), 15.0),
        ((1.0, 1e-3), (1.0, 1.0), (0.0, 0.0), 8.0),
        ((1.0, 1.2, 3.0), (3000.0, 3000.0, 2.0), (0.0, 0.0, 1.0), 6700.0),
    ],
)
def test_the_quadratic_forms_survival_is_that_of_its_draws(
    weights: tuple[float, ...],
    dofs: tuple[float, ...],
    noncentralities: tuple[float, ...],
    x: float,
) -> None:
    """Imhof's integral against 200,000 draws of the weighted sum, within 5 SE."""
    rng = np.random.default_rng(7)
    n = 200_000
    draws = sum(
        w * rng.noncentral_chisquare(h, nc, n) if nc > 0 else w * rng.chisquare(h, n)
        for w, h, nc in zip(weights, dofs, noncentralities, strict=True)
    )
    ours = distributions.quadratic_form_sf(x, weights, dofs, noncentralities)
    rate = float(np.mean(draws > x))
    assert abs(ours - rate) < 5 * math.sqrt(max(rate * (1 - rate), 1e-6) / n) + 1e-5, (ours, rate)


def test_a_quadratic_form_of_equal_weights_is_a_noncentral_chi_square() -> None:
    assert distributions.quadratic_form_sf(12.0, (2.0, 2.0), (3.0, 4.0), (1.0, 0.5)) == (
        pytest.approx(float(stats.ncx2.sf(6.0, 7.0, 1.5)), rel=1e-9)
    )
    # nearly equal weights through the integral give the same
    near = distributions.quadratic_form_sf(12.0, (2.0, 2.0 * (1 + 1e-9)), (3.0, 4.0), (1.0, 0.5))
    assert near == pytest.approx(float(stats.ncx2.sf(6.0, 7.0, 1.5)), abs=1e-7)
    assert distributions.quadratic_form_sf(-1.0, (1.0, 2.0), (1.0, 1.0)) == 1.0
