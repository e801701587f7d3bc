"""The five observables of a set of trials (eqs. 15-19)."""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
import numpy.typing as npt

from odohil.errors import MeasurementError


@dataclass(frozen=True)
class Observables:
    """phi1..phi5 of n trials of one motion, SI.

    Attributes:
        phi1: mean heading change Delta, rad (eq. 15).
        phi2: sample variance of Delta with n - 1, rad^2 (eq. 16).
        phi3: mean x of the end point, m (eq. 17).
        phi4: mean y of the end point, m (eq. 18).
        phi5: mean of x^2 + y^2, m^2 (eq. 19). A raw second moment about the
            start point, not a variance: it measures the spread only for a
            closed path, whose end point is expected near the start.
        n_trials: number of trials n.
    """

    phi1: float
    phi2: float
    phi3: float
    phi4: float
    phi5: float
    n_trials: int

    def as_dict(self) -> dict[str, float]:
        """phi1..phi5 keyed by name (SI)."""
        return {key: value for key, value in asdict(self).items() if key != "n_trials"}


def observables(pose_changes: npt.ArrayLike) -> Observables:
    """phi1..phi5 from the pose changes of n >= 2 trials.

    Args:
        pose_changes: shape (n, 3): x (m), y (m) of the end point in the start
            frame and heading change Delta (rad), one row per trial.

    Raises:
        MeasurementError: not an (n, 3) array with n >= 2, or not finite.
    """
    data = np.asarray(pose_changes, dtype=np.float64)
    if data.ndim != 2 or data.shape[1] != 3:
        raise MeasurementError(f"pose changes must have shape (n, 3), got {data.shape}")
    if data.shape[0] < 2:
        raise MeasurementError(f"phi2 needs at least 2 trials, got {data.shape[0]}")
    if not np.all(np.isfinite(data)):
        raise MeasurementError("pose changes must be finite numbers")
    x, y, delta = data[:, 0], data[:, 1], data[:, 2]
    return Observables(
        phi1=float(delta.mean()),
        phi2=float(delta.var(ddof=1)),
        phi3=float(x.mean()),
        phi4=float(y.mean()),
        phi5=float(np.mean(x * x + y * y)),
        n_trials=int(data.shape[0]),
    )
