"""Trials as the estimators see them, and their per-design sufficient statistics.

For a Gaussian model, the trials of one design that share a measurement
covariance enter the likelihood only through n, sum(v) and sum(v v^T), with
v = (x m, y m, Delta rad). A :class:`TrialGroup` keeps exactly those, so the
cost of an estimate grows with the number of groups, not of trials.

Headings are known modulo 2 pi. Each group keeps a reference heading c (the
circular mean of its first trials) and stores every Delta unwrapped to within
pi of c; the model mean is later moved by a multiple of 2 pi to within pi of c
(:func:`align_heading`). While the spread of Delta is well below pi this is the
same as unwrapping every trial relative to the model mean.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from odohil.science.grouping import by_design
from odohil.science.path_trials import checked_measurement
from odohil.science.paths import Design, FloatArray
from odohil.units import angle_near, circular_mean


@dataclass(frozen=True)
class Observation:
    """One trial: a design, its measured pose change and the measurement's covariance.

    Attributes:
        design: the forth-and-back design driven.
        pose_change: (3,): x (m), y (m) of the end point in the start frame and
            heading change Delta (rad) minus the path's winding; Delta may be
            given modulo 2 pi.
        measurement_cov: (3, 3) covariance of the measured pose change (m^2,
            m rad, rad^2); zeros when the pose is exact.
        line: where the trial came from (line number in a trial file), or None.
        trial: the trial's number (the plan's trial number in a session, the
            1-based row in a trial file), or None; how users name the trial.
    """

    design: Design
    pose_change: FloatArray
    measurement_cov: FloatArray = field(default_factory=lambda: np.zeros((3, 3)))
    line: int | None = None
    trial: int | None = None

    def __post_init__(self) -> None:
        pose, cov = checked_measurement(self.where(), self.pose_change, self.measurement_cov)
        object.__setattr__(self, "pose_change", pose)
        object.__setattr__(self, "measurement_cov", cov)

    def where(self) -> str:
        """``trial N (design)`` when the trial number is known, else ``line N``,
        else ``a trial``."""
        if self.trial is not None:
            return f"trial {self.trial} ({self.design.label()})"
        return f"line {self.line}" if self.line is not None else "a trial"


def align_heading(mean: FloatArray, reference: float) -> FloatArray:
    """A copy of a model mean (x, y, Delta) with Delta moved by a multiple of
    2 pi to within pi of ``reference`` (rad)."""
    out = np.array(mean, dtype=np.float64)
    out[2] = angle_near(float(out[2]), reference)
    return out


@dataclass
class TrialGroup:
    """Sufficient statistics of the trials of one design with one measurement covariance.

    Mutable on purpose: :class:`~odohil.science.estimators.incremental.IncrementalEstimator`
    adds trials one at a time.

    Attributes:
        design: the design.
        reference: heading every Delta is unwrapped near, rad.
        n: number of trials.
        total: sum of v, (3,).
        outer: sum of v v^T, (3, 3).
        measurement_total: sum of the trials' measurement covariances, (3, 3).
        weight: sum of the trials' weights (n when every weight is 1); total
            and outer are weighted sums, for the robust fit's M-step.
    """

    design: Design
    reference: float
    n: int = 0
    total: FloatArray = field(default_factory=lambda: np.zeros(3))
    outer: FloatArray = field(default_factory=lambda: np.zeros((3, 3)))
    measurement_total: FloatArray = field(default_factory=lambda: np.zeros((3, 3)))
    weight: float = 0.0

    @property
    def key(self) -> Design:
        """The group's key in a model point: its design."""
        return self.design

    def unwrapped(self, pose_change: FloatArray) -> FloatArray:
        """The pose change with Delta within pi of the reference."""
        return align_heading(pose_change, self.reference)

    def add(self, observation: Observation, weight: float = 1.0) -> None:
        """Fold one trial in, with a weight (0 to 1) on its residual."""
        v = self.unwrapped(observation.pose_change)
        self.n += 1
        self.weight += weight
        self.total = self.total + weight * v
        self.outer = self.outer + weight * np.outer(v, v)
        self.measurement_total = self.measurement_total + observation.measurement_cov

    @property
    def mean(self) -> FloatArray:
        """(Weighted) mean of v."""
        return self.total / self.weight

    @property
    def measurement_cov(self) -> FloatArray:
        """Mean measurement covariance of the group's trials, (3, 3)."""
        return self.measurement_total / self.n


def measurement_key(cov: FloatArray, relative_bin: float | None) -> tuple[float, ...]:
    """A grouping key for a measurement covariance.

    ``relative_bin=None``: the exact values (trials share a group only when
    their covariances are identical). Otherwise standard deviations are binned
    on a log scale with bins ``relative_bin`` wide (0.1: 10 %) and
    correlations in steps of ``relative_bin`` (0 variances form their own bin).
    """
    if relative_bin is None:
        return tuple(float(v) for v in cov.reshape(-1))
    sd = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    sd_bins = tuple(
        -math.inf if s == 0.0 else float(round(math.log(s) / math.log1p(relative_bin))) for s in sd
    )
    corr_bins: list[float] = []
    for i, j in ((0, 1), (0, 2), (1, 2)):
        denom = sd[i] * sd[j]
        corr = float(cov[i, j] / denom) if denom > 0 else 0.0
        corr_bins.append(float(round(corr / relative_bin)))
    return sd_bins + tuple(corr_bins)


def group_trials(
    observations: Sequence[Observation], relative_bin: float | None = None
) -> list[TrialGroup]:
    """Sufficient statistics of the trials, one group per design and measurement key.

    Every design's reference heading is the circular mean of its trials' Delta.
    A trial driven backwards is folded into its forward design as its mirror
    image (:func:`mirrored`), which the model distributes exactly alike.
    """
    observations = [forward_view(o) for o in observations]
    references = {
        design: circular_mean([o.pose_change[2] for o in members])
        for design, members in by_design(observations).items()
    }
    groups: dict[tuple[Design, tuple[float, ...]], TrialGroup] = {}
    for obs in observations:
        key = (obs.design, measurement_key(obs.measurement_cov, relative_bin))
        if key not in groups:
            groups[key] = TrialGroup(obs.design, references[obs.design])
        groups[key].add(obs)
    return list(groups.values())


_MIRROR = np.diag([-1.0, 1.0, -1.0])


def mirrored(observation: Observation) -> Observation:
    """The trial as its design driven the other way would show it: x and
    Delta negated, the measurement covariance transformed alike (see
    :mod:`odohil.science.paths`: a backward path's pose change is
    distributed as (-x, y, -Delta) of the forward one)."""
    return replace(
        observation,
        design=observation.design.mirrored,
        pose_change=_MIRROR @ np.asarray(observation.pose_change, dtype=np.float64),
        measurement_cov=_MIRROR @ np.asarray(observation.measurement_cov) @ _MIRROR,
    )


def forward_view(observation: Observation) -> Observation:
    """The trial as the estimators model it: a backward trial as its forward
    design's mirror image (:func:`mirrored`), any other trial as it is."""
    return mirrored(observation) if observation.design.backward else observation


@dataclass(frozen=True)
class DesignSummary:
    """The pooled statistics of one design (all its groups).

    Attributes:
        design: the design.
        n: number of trials.
        mean: mean of v = (x, y, Delta), Delta unwrapped near the reference.
        scatter: sum of (v - mean)(v - mean)^T, (3, 3).
        measurement_cov: mean measurement covariance, (3, 3).
        reference: the reference heading, rad.
    """

    design: Design
    n: int
    mean: FloatArray
    scatter: FloatArray
    measurement_cov: FloatArray
    reference: float

    @property
    def mean_square_distance(self) -> float:
        """Mean of x^2 + y^2, m^2 (phi5)."""
        second = (self.scatter + self.n * np.outer(self.mean, self.mean)) / self.n
        return float(second[0, 0] + second[1, 1])

    @property
    def heading_variance(self) -> float:
        """Sample variance of Delta with n - 1 (phi2), rad^2; nan for one trial."""
        return float(self.scatter[2, 2] / (self.n - 1)) if self.n > 1 else math.nan


def summarise(groups: Sequence[TrialGroup]) -> list[DesignSummary]:
    """Pool the groups of each design (Delta re-aligned to the design's first reference)."""
    out = []
    for design, members in by_design(g for g in groups if g.n > 0).items():
        reference = members[0].reference
        n = sum(g.n for g in members)
        total = np.zeros(3)
        outer = np.zeros((3, 3))
        meas = np.zeros((3, 3))
        for g in members:
            shift = np.zeros(3)
            shift[2] = align_heading(g.mean, reference)[2] - g.mean[2]
            total += g.total + g.n * shift
            outer += (
                g.outer + np.outer(g.total, shift) + np.outer(shift, g.total)
            ) + g.n * np.outer(shift, shift)
            meas += g.measurement_total
        mean = total / n
        scatter = outer - n * np.outer(mean, mean)
        out.append(DesignSummary(design, n, mean, 0.5 * (scatter + scatter.T), meas / n, reference))
    return out
