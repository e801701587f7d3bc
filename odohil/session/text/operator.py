"""What the wizard says to the operator beside the robot, in plain words: a
trial's header and what was already entered, the marks to make, where the
encoders put the robot, the questions to measure again or once more, putting
the robot back, a rejection and a solved trial. The wizard styles and prints
them; what the operator must do is the session's (beside
odohil/session/wizard/tape_entry.py, which asks for the distances themselves). Also
what ``run`` says of its simulated operator measuring again."""

from __future__ import annotations

import math
from collections.abc import Collection, Sequence

from odohil import units
from odohil.science.robot_description import RobotDescription
from odohil.session.journal.state import CompletedTrial
from odohil.session.measure.protocol import TrialContext
from odohil.session.measure.tape.records import TapeContext
from odohil.session.run.start_pose import HERE

__all__ = [
    "END_MARKS",
    "encoders_at_end",
    "entered_so_far",
    "extra_distance_prompt",
    "measure_again",
    "put_back_prompt",
    "remeasure_prompt",
    "solved",
    "start_marks",
    "trial_header",
]

END_MARKS = "Mark the floor at the screws again (end marks), then press Enter: "


def trial_header(ctx: TrialContext, resumed: bool) -> str:
    """``Trial 3/60 (attempt 1): k=1 l=6 m, 12 m of driving.``; a resumed
    attempt says that its motion is done and its marks are on the floor."""
    note = " (resumed: the motion is done, its marks are on the floor)" if resumed else ""
    return (
        f"Trial {ctx.trial}/{ctx.n_trials} (attempt {ctx.attempt}): "
        f"{ctx.design.label()}, {ctx.design.distance_m:g} m of driving{note}."
    )


def entered_so_far(ctx: TapeContext) -> str | None:
    """The distances of a resumed attempt already entered (None: none)."""
    if not ctx.measurements:
        return None
    values = zip(ctx.labels, ctx.measurements, strict=False)
    entered = ", ".join(f"{label} = {value:.4f} m" for label, value in values)
    left = units.plural(len(ctx.labels) - len(ctx.measurements), "distance")
    return f"Already entered and saved: {entered}; {left} to go."


def start_marks(description: RobotDescription) -> str:
    """The prompt before a motion: mark the floor at every screw."""
    names = ", ".join(description.screw_names)
    return (
        f"Mark the floor at the {len(description.screws)} screws ({names}), "
        "keep clear of the robot, then press Enter to start the motion: "
    )


def encoders_at_end(pose: tuple[float, float, float]) -> str:
    """Where the encoders put the robot after the motion, from its start."""
    return (
        f"Motion done; encoders say x={pose[0]:+.4f} m y={pose[1]:+.4f} m "
        f"heading {math.degrees(pose[2]):+.2f} deg from the start."
    )


def remeasure_prompt(ctx: TapeContext, index: int) -> str:
    """The slip check doubts distance ``index``: measure it again (Enter keeps it)."""
    typed = ctx.measurements[index]
    return (
        f"Re-measure {ctx.labels[index]}, metres (you typed {typed:.4f}; press Enter to keep it): "
    )


def extra_distance_prompt(label: str) -> str:
    """The trial is ambiguous: measure one more cross distance (Enter: leave the trial out)."""
    skip = "press Enter if you cannot; the trial is then left out"
    return f"Measure one more distance, {label}, metres ({skip}): "


def put_back_prompt(trial: int) -> str:
    """The robot is off trial ``trial``'s start: put it back, or start where it stands."""
    return (
        f"Put the robot back where trial {trial} starts (the end marks of the last trial, "
        f"or this trial's start marks), then press Enter; or type '{HERE}' to start the "
        "trial where it stands: "
    )


def measure_again(ctx: TapeContext, kept: Collection[int]) -> str:
    """Which distances a rejection asks for again: those not ``kept`` (indices)."""
    again = ", ".join(label for i, label in enumerate(ctx.labels) if i not in kept)
    what = f"only {again} (the other distances are kept)" if kept else "all its distances"
    return f"Measure again {what}."


def solved(trial: CompletedTrial) -> str:
    """``Trial 4 solved: dx=+1.2 mm dy=-0.4 mm dtheta=+0.012 deg`` (and a doubt)."""
    x, y, theta = trial.pose_change
    return (
        f"Trial {trial.trial} solved: dx={1e3 * x:+.1f} mm dy={1e3 * y:+.1f} mm "
        f"dtheta={math.degrees(theta):+.3f} deg"
        + ("" if trial.clear_cut else f" (not clear-cut: {trial.note})")
    )


def measured_again(trial: int, who: str) -> str:
    """The distances ``who`` took in ``trial`` fit no rigid motion and were taken again."""
    return (
        f"trial {trial}: the distances {who} took fit no rigid motion, so {who} measured "
        "them again: the check at work; nothing is lost and the trial counts once (the "
        "reason is in the journal)."
    )


def remeasured(trials: Sequence[int], who: str) -> str:
    """The slip check had ``who`` take a doubted distance again in ``trials``."""
    return (
        f"In {units.plural(len(trials), 'trial')} ({', '.join(map(str, trials))}) the slip "
        f"check doubted a distance and {who} measured it again: the check at work; nothing "
        "is lost and each trial counts once."
    )
