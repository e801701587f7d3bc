"""The ``PoseSource`` protocol: where a trial's real pose change comes from.

The session owns this protocol. The engine calls, per trial attempt:

1. ``at_start`` with the robot at rest and its odometry re-zeroed (a tape
   operator marks the floor; motion capture takes a still-window pose; the
   fake's truth channel reads the true pose);
2. ``at_end`` once the motion is over and the robot is at rest again;
3. ``pose_change``: the real pose change of the trial in its start frame,
   with its covariance, or None when the trial cannot be measured unambiguously
   (it is then journaled and left out of every estimate).

What ``at_start`` and ``at_end`` return is journaled with the trial and handed
back in the context (``TrialContext.start`` / ``.end``), so a resumed session
gives a source the same data. A source that takes several readings (the tape:
one distance at a time, re-measures) journals each through ``log`` before it
goes on, so nothing the operator typed is lost.

Sources: the tape with the floor-marks solver, the fake robot's truth
channel, a trial file of poses, motion capture over tcp.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Protocol

from odohil.session.sources import TrialContext

Covariance3 = tuple[
    tuple[float, float, float], tuple[float, float, float], tuple[float, float, float]
]
"""A 3x3 covariance of (x m, y m, theta rad): m^2, m^2, rad^2 on the diagonal."""


@dataclass(frozen=True)
class MeasuredPose:
    """One trial's measured real pose change.

    Attributes:
        pose: (x m, y m, theta rad in (-pi, pi]) of the end pose in the start
            pose's frame.
        covariance: its measurement covariance (see :data:`Covariance3`).
        flagged: the operator kept a value the slip check doubted.
        note: how it was obtained (for the journal and the report).
    """

    pose: tuple[float, float, float]
    covariance: Covariance3
    flagged: bool = False
    note: str = ""


class MeasurementLog(Protocol):
    """Journals a source's intermediate readings (fsync before it returns)."""

    def __call__(self, kind: str, data: Mapping[str, Any]) -> None: ...


class PoseSource(Protocol):
    """Where a trial's real pose change comes from (see the module docstring)."""

    def at_start(self, ctx: TrialContext) -> Mapping[str, Any]:
        """The robot rests at the trial's start; JSON data to journal."""
        ...

    def at_end(self, ctx: TrialContext) -> Mapping[str, Any]:
        """The robot rests at the trial's end; JSON data to journal."""
        ...

    def pose_change(self, ctx: TrialContext, log: MeasurementLog) -> MeasuredPose | None:
        """The trial's real pose change, or None when it stays ambiguous.

        Raises MeasurementError when it cannot be had at all."""
        ...
