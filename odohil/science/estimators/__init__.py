"""Estimators of the four odometry error parameters from trials.

- :func:`estimate`: the paper's sequential method (``method="paper"``) or
  joint maximum likelihood (``method="joint"``), with model and sufficiency
  checks, as an :class:`EstimateResult`;
- :class:`IncrementalEstimator`: maximum likelihood refreshed one trial at a time.
"""

from odohil.science.estimators.checks import Criteria
from odohil.science.estimators.estimate import METHODS, Method, estimate
from odohil.science.estimators.incremental import IncrementalEstimator
from odohil.science.estimators.observations import Observation
from odohil.science.estimators.result import (
    EstimateResult,
    ModelCheck,
    Outlier,
    ParameterEstimate,
    Sufficiency,
    Suggestion,
)

__all__ = [
    "METHODS",
    "Criteria",
    "EstimateResult",
    "IncrementalEstimator",
    "Method",
    "ModelCheck",
    "Observation",
    "Outlier",
    "ParameterEstimate",
    "Sufficiency",
    "Suggestion",
    "estimate",
]
