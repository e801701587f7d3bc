"""Where the tape's distances come from: the :class:`MeasurementSource` protocol.

A :class:`MeasurementSource` is asked three things per trial attempt:
``mark_start`` once the robot is re-zeroed (the operator marks the floor under
every screw), ``mark_end`` once the motion is done (the end marks), then one
``distance`` per tape reading, in the robot description's order (same-screw
distances, then cross distances). Whatever ``mark_start``/``mark_end`` return
is journaled with the trial, so a resumed session hands the same data back.
A distance source sees each attempt as a
:class:`~odohil.session.measure.tape.records.TapeContext`: the generic context with
the distances' names and the tape's readings so far.

- :class:`OperatorSource`: a person with a tape, through an
  :class:`OperatorPrompts` implementation (the interactive wizard's);
- :class:`FakeTruthSource`: the fake robot's true pose (its side channel,
  behind the :class:`~odohil.session.measure.truth.TruthReader` protocol),
  turned into distances by the forward model plus seeded Gaussian tape noise,
  for unattended runs and CI;
- :class:`RecordedSource`: distances recorded beforehand, one row per trial
  in trial order (e.g. from a trial file).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from odohil.errors import InconsistentMeasurementError, MeasurementError
from odohil.science.floor_marks import (
    distance_labels,
    marks_from_pose,
)
from odohil.science.paths import Design
from odohil.science.robot_description import RobotDescription
from odohil.session.measure.protocol import TrialContext
from odohil.session.measure.tape.records import TapeContext
from odohil.session.measure.truth import TruthReader, true_pose_change
from odohil.session.trials.trial_file import read_trials

__all__ = [
    "FakeTruthSource",
    "MeasurementSource",
    "OperatorPrompts",
    "OperatorSource",
    "RecordedSource",
    "recorded_source_from_file",
]


class MeasurementSource(Protocol):
    """Where distances come from (see the module docstring)."""

    def mark_start(self, ctx: TapeContext) -> Mapping[str, Any]:
        """The start marks are made now (the robot stands still, re-zeroed).

        Returns JSON data to journal with the trial (may be empty)."""
        ...

    def mark_end(self, ctx: TapeContext) -> Mapping[str, Any]:
        """The motion is over: the end marks are made now. Returns JSON data."""
        ...

    def distance(self, ctx: TapeContext, index: int) -> float:
        """Distance number ``index`` (label ``ctx.labels[index]``), metres.

        Raises MeasurementError when it cannot be had."""
        ...

    def rejected(self, ctx: TapeContext, rejection: InconsistentMeasurementError) -> None:
        """The distances of this attempt explain no rigid motion (``rejection``
        says why and names the suspect distances in its ``labels``); they will
        be asked for again (raise MeasurementError to give up instead)."""
        ...

    def remeasure(self, ctx: TapeContext, index: int, reason: str) -> float | None:
        """The slip check doubts the trial and suspects distance ``index``
        (``reason`` says why): that distance taken again, metres, or None to
        keep the value taken (the trial is then flagged)."""
        ...

    def extra_distance(
        self, ctx: TapeContext, pair: tuple[str, str], label: str, reason: str
    ) -> float | None:
        """The trial is ambiguous (``reason``): the cross distance from the start
        mark of screw ``pair[0]`` to the end mark of ``pair[1]`` (named
        ``label``), metres, or None when it cannot be had (the trial is then
        left out of the estimate)."""
        ...


class OperatorPrompts(Protocol):
    """The operator's side of a measurement (implemented by a user interface)."""

    def confirm_start_marks(self, ctx: TapeContext) -> None:
        """Ask the operator to mark the floor under every screw; return when done."""
        ...

    def confirm_end_marks(self, ctx: TapeContext) -> None:
        """Ask the operator to mark the end positions; return when done."""
        ...

    def ask_distance(self, ctx: TapeContext, index: int) -> float:
        """Ask for distance ``ctx.labels[index]``; return it in metres (the
        interface parses what was typed, once, and asks again until it is a
        distance)."""
        ...

    def show_rejection(self, ctx: TapeContext, rejection: InconsistentMeasurementError) -> None:
        """Tell the operator the distances are inconsistent and will be retaken
        (those ``rejection.labels`` names, or all when it names none)."""
        ...

    def ask_remeasure(self, ctx: TapeContext, index: int, reason: str) -> float | None:
        """Ask to measure distance ``ctx.labels[index]`` again (``reason``: the
        slip check's message); return it in metres, or None to keep the value."""
        ...

    def ask_extra_distance(self, ctx: TapeContext, label: str, reason: str) -> float | None:
        """Ask for one more cross distance, ``label`` (e.g. ``A start to C end``),
        because the trial is ambiguous (``reason``); return it in metres, or
        None when it cannot be measured."""
        ...


class OperatorSource:
    """A person with a tape, through :class:`OperatorPrompts`. The numbers the
    interface parsed are handed on as they are: :class:`TapeSource` checks
    every distance, from any source, once (:func:`check_distance`)."""

    def __init__(self, prompts: OperatorPrompts) -> None:
        self.prompts = prompts

    def mark_start(self, ctx: TapeContext) -> Mapping[str, Any]:
        """Wait for the operator's start marks."""
        self.prompts.confirm_start_marks(ctx)
        return {}

    def mark_end(self, ctx: TapeContext) -> Mapping[str, Any]:
        """Wait for the operator's end marks."""
        self.prompts.confirm_end_marks(ctx)
        return {}

    def distance(self, ctx: TapeContext, index: int) -> float:
        """Ask the operator for the distance, metres."""
        return self.prompts.ask_distance(ctx, index)

    def rejected(self, ctx: TapeContext, rejection: InconsistentMeasurementError) -> None:
        """Tell the operator."""
        self.prompts.show_rejection(ctx, rejection)

    def remeasure(self, ctx: TapeContext, index: int, reason: str) -> float | None:
        """Ask the operator to re-enter the suspect distance; None keeps it."""
        return self.prompts.ask_remeasure(ctx, index, reason)

    def extra_distance(
        self, ctx: TapeContext, pair: tuple[str, str], label: str, reason: str
    ) -> float | None:
        """Ask the operator for the named cross distance; None if skipped."""
        return self.prompts.ask_extra_distance(ctx, label, reason)


class FakeTruthSource:
    """Distances from the fake robot's true pose, with simulated tape noise.

    At ``mark_start`` and ``mark_end`` the true pose is read from the side
    channel and journaled (``true_pose``). Distances are the forward model of
    the true pose change plus independent N(0, ``sigma_m``^2) noise (the
    robot description's tape sigma by default), folded at 0. The noise of a
    trial attempt is drawn from a generator seeded by (seed, trial, attempt,
    rejections), so a resumed session measures exactly what the interrupted
    one would have.
    """

    def __init__(
        self,
        truth: TruthReader,
        description: RobotDescription,
        seed: int = 0,
        sigma_m: float | None = None,
    ) -> None:
        self.truth = truth
        self.description = description
        self.seed = seed
        self.sigma_m = description.sigma_m if sigma_m is None else sigma_m

    def mark_start(self, ctx: TapeContext) -> Mapping[str, Any]:
        """Journal the true start pose."""
        return {"true_pose": list(self.truth.true_pose())}

    def mark_end(self, ctx: TapeContext) -> Mapping[str, Any]:
        """Journal the true end pose."""
        return {"true_pose": list(self.truth.true_pose())}

    def true_pose_change(self, ctx: TrialContext) -> tuple[float, float, float]:
        """The attempt's true (dx m, dy m, dtheta rad), dtheta minus the winding."""
        return true_pose_change(ctx)

    def distance(self, ctx: TapeContext, index: int) -> float:
        """The noisy forward-model distance number ``index``, metres."""
        return self._draw(ctx, index, [self.seed, ctx.trial, ctx.attempt, ctx.rejections])

    def _draw(self, ctx: TapeContext, index: int, seed: list[int]) -> float:
        exact = marks_from_pose(self.description, self.true_pose_change(ctx)).as_array()
        rng = np.random.default_rng(seed)
        noisy = np.abs(exact + rng.normal(0.0, self.sigma_m, exact.size))
        return float(noisy[index])

    def rejected(self, ctx: TapeContext, rejection: InconsistentMeasurementError) -> None:
        """Nothing to do: the next draw differs (``rejections`` is in the seed)."""

    def remeasure(self, ctx: TapeContext, index: int, reason: str) -> float:
        """The suspect distance with a new noise draw (seeded by the attempt and
        the number of re-measures so far)."""
        seed = [self.seed, ctx.trial, ctx.attempt, ctx.rejections, 1 + ctx.remeasures]
        return self._draw(ctx, index, seed)

    def extra_distance(
        self, ctx: TapeContext, pair: tuple[str, str], label: str, reason: str
    ) -> None:
        """An unattended run takes no extra distances: the trial is left out."""
        return None


class RecordedSource:
    """Distances taken beforehand: row k (1-based) serves trial k of the plan
    (every attempt at it). Each row holds the distances in the robot
    description's order; with ``designs``, row k must be of trial k's design.
    """

    def __init__(
        self,
        rows: Sequence[Sequence[float]],
        description: RobotDescription,
        origin: str,
        designs: Sequence[Design] | None = None,
    ) -> None:
        labels = distance_labels(description)
        for number, row in enumerate(rows, start=1):
            if len(row) != len(labels):
                raise MeasurementError(
                    f"{origin}: row {number} has {len(row)} distances, "
                    f"the robot description needs {len(labels)} ({', '.join(labels)})"
                )
        self.rows = [tuple(float(v) for v in row) for row in rows]
        self.origin = origin
        self.designs = tuple(designs) if designs is not None else None

    def row_for(self, ctx: TapeContext) -> int:
        """The row used by trial ``ctx.trial`` (trial k uses row k - 1)."""
        return ctx.trial - 1

    def mark_start(self, ctx: TapeContext) -> Mapping[str, Any]:
        """Nothing to mark; journal which row serves the trial."""
        return {"row": self.row_for(ctx) + 1, "origin": self.origin}

    def mark_end(self, ctx: TapeContext) -> Mapping[str, Any]:
        """Nothing to mark."""
        return {}

    def distance(self, ctx: TapeContext, index: int) -> float:
        """Distance ``index`` of the trial's row."""
        row = self.row_for(ctx)
        if row >= len(self.rows):
            raise MeasurementError(
                f"{self.origin}: trial {ctx.trial} needs row {row + 1}, "
                f"the file has {len(self.rows)}"
            )
        if self.designs is not None and self.designs[row] != ctx.design:
            raise MeasurementError(
                f"{self.origin}: row {row + 1} is design {self.designs[row].label()}, "
                f"trial {ctx.trial} runs {ctx.design.label()}"
            )
        return self.rows[row][index]

    def remeasure(self, ctx: TapeContext, index: int, reason: str) -> None:
        """Recorded distances cannot be retaken: keep the value (the trial is flagged)."""
        return None

    def extra_distance(
        self, ctx: TapeContext, pair: tuple[str, str], label: str, reason: str
    ) -> None:
        """Recorded sessions have no extra distances: the trial is left out."""
        return None

    def rejected(self, ctx: TapeContext, rejection: InconsistentMeasurementError) -> None:
        """Recorded distances cannot be retaken."""
        raise MeasurementError(
            f"{self.origin}: row {self.row_for(ctx) + 1} (trial {ctx.trial}): {rejection}"
        )


def recorded_source_from_file(path: str | Path, description: RobotDescription) -> RecordedSource:
    """A :class:`RecordedSource` from a trial file: raw-mark rows give their
    distances; pose rows give the exact distances their pose change leaves
    (forward model). Row k serves trial k and must be of its design.

    Raises:
        TrialFileError: bad rows (all listed).
    """
    trials = read_trials(path, description)
    rows = [
        tuple(
            float(v)
            for v in (
                trial.marks.as_array()
                if trial.marks is not None
                else marks_from_pose(description, trial.pose_change).as_array()
            )
        )
        for trial in trials.trials
    ]
    return RecordedSource(
        rows, description, origin=str(path), designs=[t.design for t in trials.trials]
    )
