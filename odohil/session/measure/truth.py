"""The fake robot's true pose: :class:`TruthPoseSource` and the pose change it reads.

:class:`TruthPoseSource` is a pose source giving the fake robot's true pose
change from its truth channel (the :class:`TruthReader` protocol), with seeded
Gaussian pose noise; :func:`true_pose_change` is that change in the trial's
start frame, which the fake tape (odohil/session/measure/tape/distances.py)
turns into distances.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any, Protocol

import numpy as np

from odohil.errors import MeasurementError
from odohil.science import frames
from odohil.session.measure.protocol import (
    MeasuredPose,
    MeasurementLog,
    Pose,
    TrialContext,
    as_covariance,
    as_pose,
)

__all__ = [
    "TruthPoseSource",
    "TruthReader",
    "relative_true_pose",
    "true_pose_change",
]


class TruthReader(Protocol):
    """The fake robot's side channel: its true pose now."""

    def true_pose(self) -> tuple[float, float, float]:
        """True (x m, y m, heading rad) in the robot's power-on frame."""
        ...


def relative_true_pose(
    start: Sequence[float], end: Sequence[float], winding_rad: float
) -> tuple[float, float, float]:
    """The true pose change from two true poses (x m, y m, heading rad): the end
    point in the start frame, and the heading change minus ``winding_rad``."""
    x, y, turned = frames.relative_pose(start, end)
    return (x, y, turned - winding_rad)


class TruthPoseSource:
    """The fake robot's truth channel as a :class:`PoseSource`: the true pose
    change (journaled true start and end poses, minus the design's winding)
    plus independent Gaussian noise of standard deviations ``sigma`` (x m,
    y m, theta rad), drawn from a generator seeded by (seed, trial, attempt),
    so a resumed session measures what the interrupted one would have."""

    def __init__(
        self, truth: TruthReader, sigma: tuple[float, float, float], seed: int = 0
    ) -> None:
        if not all(math.isfinite(v) and v > 0 for v in sigma):
            raise MeasurementError(f"pose noise sigmas must be positive, got {sigma!r}")
        self.truth = truth
        self.sigma = sigma
        self.seed = seed

    def at_start(self, ctx: TrialContext) -> Mapping[str, Any]:
        """Journal the true start pose."""
        return {"true_pose": list(self.truth.true_pose())}

    def at_end(self, ctx: TrialContext) -> Mapping[str, Any]:
        """Journal the true end pose."""
        return {"true_pose": list(self.truth.true_pose())}

    def pose_change(self, ctx: TrialContext, log: MeasurementLog) -> MeasuredPose:
        """The noisy true pose change of the attempt."""
        exact = np.array(true_pose_change(ctx))
        rng = np.random.default_rng([self.seed, ctx.trial, ctx.attempt])
        sigma = np.array(self.sigma)
        noisy = exact + rng.normal(0.0, 1.0, 3) * sigma
        variances = sigma**2
        return MeasuredPose(
            pose=as_pose(noisy),
            covariance=as_covariance(np.diag(variances)),
            details={"source": "the fake robot's true pose with simulated noise"},
        )


def true_pose_change(ctx: TrialContext) -> Pose:
    """The attempt's true (dx m, dy m, dtheta rad) from the journaled true start
    and end poses, dtheta minus the design's winding.

    Raises:
        MeasurementError: no true start and end pose were journaled.
    """
    try:
        start, end = ctx.start["true_pose"], ctx.end["true_pose"]
    except KeyError:
        raise MeasurementError(
            f"trial {ctx.trial}: no true start and end pose were journaled"
        ) from None
    return relative_true_pose(start, end, ctx.design.path().winding_rad)
