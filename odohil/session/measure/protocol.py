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
one distance at a time, re-measures) journals each through ``log`` as one of
its own :class:`~odohil.session.journal.events.SourceEvent` s before it goes on, so
nothing the operator typed is lost; the session folds them into the source's
own :class:`~odohil.session.journal.events.SourceReadings` record, and ``log`` hands
back the context as the journal now stands, with that record in
``TrialContext.readings``. The context carries nothing else of any one
source: the tape's own context (distance names, rejections, re-measures) is
the tape's (odohil/session/measure/tape/records.py).

The engine checks what ``pose_change`` returns against the encoders and the
model's prediction (odohil/session/measure/plausibility.py: a doubtful pose is
flagged, an implausible one voids the attempt and stops the session), then
journals it as the trial's ``solved`` record; an ``ambiguous`` pose is
journaled and left out of every estimate.

Sources: the tape with the floor-marks solver
(odohil/session/measure/tape/source.py), the fake robot's truth channel
(odohil/session/measure/truth.py), a trial file of poses
(odohil/session/measure/files.py); motion capture over tcp
(odohil/session/measure/mocap/). ``--measure`` names one through the
registry of pose sources (odohil/session/measure/registry.py, the
``odohil.pose_sources`` entry-point group; docs/pose-sources.md), which
parses, checks and opens it.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Protocol

from odohil.science.floor_marks import PosePrior
from odohil.science.frames import Pose as Pose
from odohil.science.path_designs import PathDesign
from odohil.science.paths import Design

if TYPE_CHECKING:
    from odohil.session.journal.events import SourceEvent, SourceReadings

Covariance3 = tuple[
    tuple[float, float, float], tuple[float, float, float], tuple[float, float, float]
]
"""A 3x3 covariance of (x m, y m, theta rad): m^2, m^2, rad^2 on the diagonal."""


@dataclass(frozen=True)
class TrialContext:
    """What a source may know about the trial attempt it measures.

    Attributes:
        trial: trial number in the plan (1-based).
        attempt: attempt number (1-based).
        n_trials: trials in the plan.
        design: the design driven (forth-and-back, or a general path).
        start: the data ``at_start`` returned (journaled).
        end: the data ``at_end`` returned (journaled; empty before).
        encoder_end_pose: (x m, y m, theta rad) the odometry reported, once
            the motion is done.
        predicted: the model's predictive distribution of the pose change,
            given the odometry, at the current estimate (or the description's
            priors); None before the motion is done.
        far_s: host monotonic times (:func:`time.monotonic`, s) between which
            the encoders put the robot at least half its farthest distance from
            the start, given to ``at_end``; a source that watches the path
            reports what it saw then (None: not given, or the motion went
            nowhere).
        readings: the source's own record of the attempt's readings so far
            (folded from the :class:`~odohil.session.journal.events.SourceEvent` s it
            journaled through ``log``; the tape's:
            :class:`~odohil.session.measure.tape.records.TapeReadings`), None before
            the first; opaque to the engine.
    """

    trial: int
    attempt: int
    n_trials: int
    design: Design | PathDesign
    start: Mapping[str, Any] = field(default_factory=dict)
    end: Mapping[str, Any] = field(default_factory=dict)
    encoder_end_pose: Pose | None = None
    predicted: PosePrior | None = None
    far_s: tuple[float, float] | None = None
    readings: SourceReadings | None = None


@dataclass(frozen=True)
class MeasuredPose:
    """One trial's measured real pose change.

    Attributes:
        pose: (x m, y m, theta rad in (-pi, pi]) of the end pose in the start
            pose's frame.
        covariance: its measurement covariance (see :data:`Covariance3`).
        flagged: a reading was kept that a check doubted (the trial is
            flagged in the report).
        flag_reason: why it is flagged (journaled with the trial; the tape:
            the slip check's doubt).
        note: why the pose is in doubt ("" when it is clear-cut).
        clear_cut: the source is sure of this pose among the ones it allows.
        ambiguous: several poses stayed plausible; the trial is journaled and
            left out of every estimate.
        candidates: the plausible poses of an ambiguous trial.
        details: more JSON for the ``solved`` record (e.g. the solver's chi2).
        excursion_m: the farthest the source saw the robot from its start
            during the motion, m; None when it did not see the path.
        prediction_checked: the source already tested the pose against
            ``ctx.predicted`` and handled a doubt (the tape's slip check): the
            engine's per-trial check only refuses an implausible one
            (odohil/session/measure/plausibility.py).
    """

    pose: Pose
    covariance: Covariance3
    flagged: bool = False
    flag_reason: str = ""
    note: str = ""
    clear_cut: bool = True
    ambiguous: bool = False
    candidates: tuple[Pose, ...] = ()
    details: Mapping[str, Any] = field(default_factory=dict)
    excursion_m: float | None = None
    prediction_checked: bool = False


class MeasurementLog(Protocol):
    """Journals a source's intermediate readings (fsync before it returns) and
    hands back the trial's context as the journal now stands."""

    def __call__(self, event: SourceEvent) -> TrialContext: ...


class PoseSource(Protocol):
    """Where a trial's real pose change comes from (see the module docstring)."""

    def at_start(self, ctx: TrialContext) -> Mapping[str, Any]:
        """The robot rests at the trial's start; JSON data to journal."""
        ...

    def at_end(self, ctx: TrialContext) -> Mapping[str, Any]:
        """The robot rests at the trial's end; JSON data to journal."""
        ...

    def pose_change(self, ctx: TrialContext, log: MeasurementLog) -> MeasuredPose:
        """The trial's real pose change (``ambiguous`` when it cannot be told
        from another one).

        Raises MeasurementError when it cannot be had at all."""
        ...


def as_pose(values: Any) -> Pose:
    """Three numbers (x m, y m, theta rad) as a :data:`Pose` of floats."""
    x, y, theta = (float(v) for v in values)
    return (x, y, theta)


def as_covariance(matrix: Any) -> Covariance3:
    """A 3x3 array-like of (x m, y m, theta rad) as a :data:`Covariance3` of floats."""
    rows = [tuple(float(v) for v in row) for row in matrix]
    return (
        (rows[0][0], rows[0][1], rows[0][2]),
        (rows[1][0], rows[1][1], rows[1][2]),
        (rows[2][0], rows[2][1], rows[2][2]),
    )
