"""phi1..phi5 from trial data (eqs. 15-19)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

from odohil.errors import MeasurementError
from odohil.science.observables import observables


def test_hand_computed_example() -> None:
    data = [[1.0, 0.0, 0.1], [0.0, 2.0, 0.3], [-1.0, 2.0, 0.5]]
    obs = observables(data)
    assert obs.n_trials == 3
    assert obs.phi1 == pytest.approx(0.3)
    # deviations -0.2, 0, 0.2 -> 0.08 / (n - 1)
    assert obs.phi2 == pytest.approx(0.04)
    assert obs.phi3 == pytest.approx(0.0)
    assert obs.phi4 == pytest.approx(4.0 / 3.0)
    assert obs.phi5 == pytest.approx((1.0 + 4.0 + 5.0) / 3.0)


def test_phi2_is_unbiased_and_phi5_is_raw_second_moment() -> None:
    rng = np.random.default_rng(7)
    n_sets, n = 4000, 5
    sets = rng.normal([0.3, -0.2, 1.0], [0.5, 0.5, 2.0], size=(n_sets, n, 3))
    phi2 = np.array([observables(s).phi2 for s in sets])
    phi5 = np.array([observables(s).phi5 for s in sets])
    # E phi2 = Var Delta = 4 with n - 1; with n it would be 3.2
    se2 = phi2.std() / math.sqrt(n_sets)
    assert abs(phi2.mean() - 4.0) < 4 * se2
    # E phi5 = <x^2 + y^2> = 0.25 + 0.09 + 0.04 + 0.25, not a variance
    se5 = phi5.std() / math.sqrt(n_sets)
    assert abs(phi5.mean() - 0.63) < 4 * se5


@pytest.mark.parametrize(
    "bad",
    [
        [[0.0, 0.0, 0.0]],
        [[0.0, 0.0], [1.0, 1.0]],
        [[0.0, 0.0, math.nan], [1.0, 1.0, 1.0]],
        [0.0, 1.0, 2.0],
    ],
)
def test_rejects_unusable_data(bad: list[Any]) -> None:
    with pytest.raises(MeasurementError):
        observables(bad)
