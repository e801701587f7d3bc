"""The verdict on an estimate: trusted, doubtful or failed, with reasons.

- failed: the fit did not converge, the data are degenerate (every trial of
  a design has the same exact pose), or a parameter has no information
  (infinite standard error);
- doubtful: the model check fails, some trial is an outlier, the misfit
  checks (odohil/science/estimators/misfit.py: a group of trials biased on
  some axis, groups that differ more than their spread allows, first trials
  unlike the rest) fail, more than
  :data:`AMBIGUOUS_TOLERATED` of the trials were left out by the session as
  ambiguous, or ``turn`` trials come from a robot whose turns carry error (a
  differential drive);
- trusted: none of these.

A few ambiguous trials left out do not make an estimate doubtful: the
estimate from the others is still right within its stated uncertainty (issue 8
measured it: bench/operator_faults.py, BENCHMARKS.md); they are listed in the
estimate's notes.

Precision (the sufficiency check) does not enter: an imprecise estimate with
an honest interval is trusted; the sufficiency verdict says how to tighten it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

from odohil import units
from odohil.science.estimators.misfit import MisfitCheck
from odohil.science.estimators.observations import Observation
from odohil.science.grouping import by_design
from odohil.science.planner import DEFAULT_MIN_TRIALS_PER_DESIGN

Status = Literal["trusted", "doubtful", "failed"]

AMBIGUOUS_TOLERATED = 0.1
"""Largest fraction of a session's trials (kept plus ambiguous) that may be
left out as ambiguous with the verdict still trusted."""


def ambiguous_tolerated(n_kept: int, n_ambiguous: int) -> bool:
    """Whether ``n_ambiguous`` trials left out leave the verdict alone."""
    return n_ambiguous <= AMBIGUOUS_TOLERATED * (n_kept + n_ambiguous)


@dataclass(frozen=True)
class Verdict:
    """Can the estimate be trusted?

    Attributes:
        status: ``trusted``, ``doubtful`` or ``failed``.
        reasons: one sentence per reason (empty when trusted).
    """

    status: Status
    reasons: tuple[str, ...] = ()

    @property
    def trusted(self) -> bool:
        """Whether the status is ``trusted``."""
        return self.status == "trusted"

    def to_json_dict(self) -> dict[str, Any]:
        """{"status", "reasons"}."""
        return {"status": self.status, "reasons": list(self.reasons)}


TRUSTED = Verdict("trusted")
"""The verdict without reasons."""


def degenerate_designs(observations: Sequence[Observation]) -> list[str]:
    """Labels of designs with 2 or more trials whose exact poses are all identical."""
    out = []
    for design, mine in by_design(observations).items():
        if len(mine) < 2 or any(np.any(o.measurement_cov != 0) for o in mine):
            continue
        poses = np.array([o.pose_change for o in mine])
        if np.all(np.ptp(poses, axis=0) == 0):
            out.append(f"{design.label()} ({units.plural(len(mine), 'trial')})")
    return out


def few_trial_designs(
    observations: Sequence[Observation], minimum: int = DEFAULT_MIN_TRIALS_PER_DESIGN
) -> list[str]:
    """``k=1 l=1 m turn (3)`` for each design (forward and backward trials
    together) with fewer than ``minimum`` trials: below the planner's minimum
    the intervals cover less than they say (3 trials of k=1 l=1 m turn on the
    Nomad's values: E_T's 95 % interval missed the truth in 12 % of 200
    simulated sessions, bench/few_trials_coverage.py)."""
    return [
        f"{design.label()} ({len(members)})"
        for design, members in by_design(observations, lambda o: o.design.forward).items()
        if len(members) < minimum
    ]


def few_trial_groups(
    labels: Sequence[str], minimum: int = DEFAULT_MIN_TRIALS_PER_DESIGN
) -> list[str]:
    """:func:`few_trial_designs` for trials labelled by their group (a general
    path's family and direction, ``square cw``): ``square cw (3)`` for each
    label with fewer than ``minimum`` trials, in order of first appearance."""
    counts: dict[str, int] = {}
    for label in labels:
        counts[label] = counts.get(label, 0) + 1
    return [f"{label} ({n})" for label, n in counts.items() if n < minimum]


def turn_designs(observations: Sequence[Observation]) -> list[str]:
    """Labels of the designs with in-place turns (``turn`` variant) among the trials."""
    designs = dict.fromkeys(o.design for o in observations)
    return [d.label() for d in designs if d.variant == "turn"]


def judge(
    observations: Sequence[Observation],
    converged: bool,
    stderr: Sequence[float],
    names: Sequence[str],
    fits: bool,
    outliers: Sequence[str],
    check_verdict: str,
    ambiguous: Sequence[int] = (),
    turns_exact: bool = True,
    misfit: MisfitCheck | None = None,
    few: Sequence[str] | None = None,
    group: str = "a design",
) -> Verdict:
    """The verdict from the fit's state and its checks (see the module docstring).

    Args:
        observations: the trials used.
        converged: whether the fit converged.
        stderr: per parameter standard error (SI).
        names: the parameters' names.
        fits: whether the model check passed.
        outliers: labels of the outlying trials.
        check_verdict: the model check's sentence.
        ambiguous: trial numbers the session left out as ambiguous.
        turns_exact: whether the robot's in-place turns carry no error (the
            paper's model); when False, ``turn`` trials make the verdict
            doubtful: their spin errors fold into E_R and K_theta unseen.
        misfit: the group-bias and trial-order checks; each failing one is a
            reason (naming the group, the axis and the bias).
        few: the groups below the minimum trials, for trials that are no
            design's (general paths: :func:`few_trial_groups`); None: the
            designs of ``observations`` (:func:`few_trial_designs`).
        group: what ``few`` counts, for the reason (``a path family and direction``).
    """
    failed: list[str] = []
    doubtful: list[str] = []
    degenerate = degenerate_designs(observations)
    if degenerate:
        failed.append(
            "degenerate data: every trial of "
            + ", ".join(degenerate)
            + " has the same pose; a real robot never repeats exactly (check the file)"
        )
    if not converged:
        failed.append("the fit did not converge")
    if few is None:
        few = few_trial_designs(observations)
    if few:
        doubtful.append(
            f"fewer than {units.plural(DEFAULT_MIN_TRIALS_PER_DESIGN, 'trial')} {group}, the "
            f"planner's minimum for honest intervals: {', '.join(few)}"
        )
    blind = [n for n, s in zip(names, stderr, strict=True) if not math.isfinite(s)]
    if blind:
        failed.append(f"not identified from these trials: {', '.join(blind)}")
    if outliers:
        doubtful.append(
            f"outliers: {', '.join(outliers)} (check them, re-measure, or leave them out "
            "with --exclude)"
        )
    elif not fits:
        doubtful.append(f"model check failed: {check_verdict}")
    if misfit is not None and not misfit.passed:
        doubtful += [f"model check failed: {reason}" for reason in misfit.reasons()]
    if ambiguous and not ambiguous_tolerated(len(observations), len(ambiguous)):
        doubtful.append(
            "ambiguous trials left out (the floor marks fit two poses): "
            + ", ".join(str(t) for t in ambiguous)
            + f" (more than {AMBIGUOUS_TOLERATED:.0%} of the trials)"
        )
    turned = turn_designs(observations) if not turns_exact else []
    if turned:
        doubtful.append(
            f"turn trials on a robot whose turns carry error: {', '.join(turned)} (the spins' "
            "errors bias E_R and K_theta; calibrate with variant=reverse)"
        )
    if failed:
        return Verdict("failed", tuple(failed + doubtful))
    if doubtful:
        return Verdict("doubtful", tuple(doubtful))
    return TRUSTED
