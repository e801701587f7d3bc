"""Model checks that see a misfit a variance can absorb: group biases and trial order.

The global goodness-of-fit test (:mod:`odohil.science.estimators.checks`) sums
every trial's squared distance. A model that lacks a term (a turn-scale error,
say) and is fitted anyway absorbs the missing mean into its variance rates:
the fitted K_theta grows until the squared distances add up again, and the
global test passes (issue 20: circles of a real robot, 95.5 on 96 dof, while
the heading residuals were +9.0 deg clockwise and -8.9 deg counter-clockwise).
What the variance cannot hide is *where* the residuals sit. This module tests
that, from the residuals alone, whatever estimator produced them:

- **group biases**: trial i's residual r_i = p_i - m_i (x m, y m, heading rad,
  the heading wrapped) has predicted covariance V_i (the model's covariance plus
  the measurement's). For every group of trials (each path family by
  direction, each direction, each family, and all trials; groups with the same
  trials are tested once; at least 2 trials) and each axis, the mean residual is
  divided by its predicted standard error and tested two-sided against N(0, 1).
  The parameters' own uncertainty enters through the mean's Jacobian J_i
  (d m_i / d parameters) and the estimate's covariance Sigma: for the trials the
  parameters were fitted on (``fitted=True``) a linear combination sum c_i r_i
  has variance sum c_i^2 V_i - (sum c_i J_i) Sigma (sum c_i J_i)^T (the fit
  pulls the residuals towards zero: the generalised-least-squares projection),
  for held-out trials ``+`` (the estimate's error moves every prediction alike).
  A group whose mean the fit pins (less than :data:`PINNED_FRACTION` of the
  variance left) is not tested: it has nothing left to say;
- **spread between groups** (``fitted=True`` only): per axis, the weighted
  one-way analysis of variance of the residuals over the finest groups (family
  by direction), F = (between / (G - 1)) / (within / (N - G)) with weights
  1 / V_i. It does not depend on the scale of the predicted variance, so a
  variance rate inflated to absorb a bias does not blind it: with a bias of b
  per-trial standard deviations between the groups F grows like n b^2 while the
  z of one group mean stays below sqrt(n);
- **trial order**: in each run of trials (a session and direction, or a family
  and direction), the first trial's residual minus the mean of the others',
  clockwise and backward runs mirrored onto the counter-clockwise and forward
  frame, pooled over the runs with inverse-variance weights, per axis,
  two-sided (the real robot's first run of each session and direction carried
  a larger heading error on circles in 11 of 12 groups, in the sense of
  turning: with opposite signs clockwise and counter-clockwise).

All tests form one family, corrected by **Holm's** step-down procedure at
:data:`MISFIT_LEVEL` (family-wise; as strong as Bonferroni's bound and never
less powerful), so that a model that is right fails this check at most at
that rate.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Literal, Protocol

import numpy as np

from odohil import units
from odohil.errors import ParameterError
from odohil.science import distributions
from odohil.science.path_trials import PathTrial
from odohil.science.paths import FloatArray, Turn
from odohil.units import wrap_angle

AXES = ("x", "y", "theta")
"""The residual components, in order: x m, y m, heading rad."""
MISFIT_LEVEL = 0.01
"""Family-wise level of the misfit checks (Holm over every test)."""
PINNED_FRACTION = 0.05
"""A group mean whose variance the fit leaves below this fraction of its
unfitted variance is pinned by the parameters and not tested."""
MIN_GROUP = 2
"""Fewest trials in a tested group."""
TURNING_RAD = 0.1
"""Total turn (rad, about 6 deg) from which a general path counts as turning
(a turn-scale error could bias it); a straight run's odometry, cut into legs,
carries turns of a few mrad."""

Kind = Literal["group", "spread", "order"]


@dataclass(frozen=True)
class TrialLabel:
    """Which groups a trial belongs to.

    Attributes:
        family: its path family or design (``"arc"``, ``"square"``,
            ``"k=1 l=3 m turn"``).
        direction: ``"forward"``/``"backward"``, ``"cw"``/``"ccw"`` or ``"mixed"``.
        run: the run of trials it was driven in (a session), for the trial-order
            check; trials of one run and direction are in driving order.
            Empty: the family and direction are the run.
        turns: whether its path turns (a turn-scale error could explain a bias).
    """

    family: str
    direction: str = "mixed"
    run: str = ""
    turns: bool = False

    @property
    def cell(self) -> str:
        """``cw arc``: the direction and family (the family alone for ``mixed``)."""
        return self.family if self.direction == "mixed" else f"{self.direction} {self.family}"

    @property
    def order_key(self) -> tuple[str, str, str]:
        """The trials compared for the trial-order check."""
        return (self.run or self.family, self.direction, self.family if self.run else "")


@dataclass(frozen=True)
class BiasTest:
    """One test of the misfit family.

    Attributes:
        kind: ``group`` (a group's mean residual), ``spread`` (the analysis of
            variance between groups) or ``order`` (first trials against the rest).
        group: what was tested, for people (``cw arc``, ``all``, ``cw``;
            for ``order`` the runs compared).
        axis: ``x``, ``y`` or ``theta``.
        n: trials in the group (runs for ``order``; groups for ``spread``).
        bias: the mean residual (the pooled first-minus-rest difference), SI
            (m or rad); for ``spread`` the largest group mean's.
        stderr: its predicted standard error, SI.
        statistic: z (``group``, ``order``) or F (``spread``).
        p_value: two-sided normal (z) or upper F tail.
        level: the Holm level it was compared with.
        rejected: whether Holm rejects it.
        detail: for ``spread``: the group named (largest |z|) and the dof.
        turns: whether the trials named turn (a turn-scale error could explain it).
    """

    kind: Kind
    group: str
    axis: str
    n: int
    bias: float
    stderr: float
    statistic: float
    p_value: float
    level: float = 0.0
    rejected: bool = False
    detail: str = ""
    turns: bool = False

    def size_text(self) -> str:
        """The bias in its axis's units: ``+9.0 deg`` or ``-3.2 mm``."""
        return _signed_text(self.axis, self.bias)

    def describe(self) -> str:
        """One sentence: what the residuals show."""
        axis = "heading" if self.axis == "theta" else self.axis
        if self.kind == "order":
            return (
                f"the first trial of each of {self.n} runs ({self.group}) carries {axis} "
                f"{self.size_text()} against the rest of its run (z = {self.statistic:.1f})"
            )
        if self.kind == "spread":
            return (
                f"{axis} residuals differ between {self.n} groups more than their spread "
                f"allows (F = {self.statistic:.3g}, {self.detail}, p = {self.p_value:.2g})"
            )
        where = (
            f"all {units.plural(self.n, 'trial')}"
            if self.group == "all"
            else f"the {units.plural(self.n, self.group + ' trial')}"
        )
        return (
            f"{axis} residual {self.size_text()} on {where} "
            f"(z = {self.statistic:.1f}, predicted SE {_abs_text(self.axis, self.stderr)})"
        )

    def to_json_dict(self) -> dict[str, Any]:
        """{"kind", "group", "axis", "n", "bias", "stderr", "statistic", "p_value",
        "level", "rejected"} (SI)."""
        out: dict[str, Any] = {
            "kind": self.kind,
            "group": self.group,
            "axis": self.axis,
            "n": self.n,
            "bias": self.bias,
            "stderr": self.stderr,
            "statistic": self.statistic,
            "p_value": self.p_value,
            "level": self.level,
            "rejected": self.rejected,
        }
        if self.detail:
            out["detail"] = self.detail
        return out


def _signed_text(axis: str, value: float) -> str:
    if axis == "theta":
        deg = math.degrees(value)
        return f"{deg:+.1f} deg" if abs(deg) >= 10 else f"{deg:+.2f} deg"
    return f"{1e3 * value:+.3g} mm"


def _abs_text(axis: str, value: float) -> str:
    return _signed_text(axis, value).lstrip("+")


@dataclass(frozen=True)
class MisfitCheck:
    """The group-bias, spread and trial-order tests of one set of residuals.

    Attributes:
        passed: no test rejected.
        level: the family-wise level (Holm).
        fitted: whether the residuals are of the trials the parameters were
            fitted on (else held out).
        tests: every test run, in the order made.
        pinned: groups (``cw arc theta``) the fit pins, not tested.
        turn_hint: the advice for a bias on trials that turn (set by the caller,
            e.g. "calibrate with turns_exact = false"); empty for none.
    """

    passed: bool
    level: float
    fitted: bool
    tests: tuple[BiasTest, ...]
    pinned: tuple[str, ...] = ()
    turn_hint: str = ""

    @property
    def correction(self) -> str:
        """How the tests are corrected for their number."""
        return f"Holm over {len(self.tests)} tests at family-wise level {self.level:g}"

    def failed(self) -> tuple[BiasTest, ...]:
        """The rejected tests, strongest first."""
        return tuple(sorted((t for t in self.tests if t.rejected), key=lambda t: t.p_value))

    def reasons(self) -> tuple[str, ...]:
        """One sentence per failing kind of test (group biases: the strongest
        per axis), each naming the group, the axis and the bias's size."""
        failed = self.failed()
        # per axis the strongest group bias, else the spread test; strongest axis first
        chosen = []
        for axis in AXES:
            mine = [t for t in failed if t.axis == axis and t.kind != "order"]
            groups = [t for t in mine if t.kind == "group"] or mine
            if groups:
                chosen.append(groups[0])
        chosen.sort(key=lambda t: t.p_value)
        out = [t.describe() + self._advice(t) for t in chosen]
        out += [
            test.describe() + ": the first trials differ (let the robot settle first, or "
            "leave them out with --exclude)"
            for test in failed
            if test.kind == "order"
        ]
        return tuple(out)

    def _advice(self, test: BiasTest) -> str:
        if test.turns and self.turn_hint:
            return f": a turn-scale error? {self.turn_hint}"
        return ": the model does not fit these trials"

    def to_json_dict(self) -> dict[str, Any]:
        """{"passed", "level", "correction", "fitted", "failed", "tests", "pinned"} (SI)."""
        return {
            "passed": self.passed,
            "level": self.level,
            "correction": "holm",
            "fitted": self.fitted,
            "failed": [t.to_json_dict() for t in self.failed()],
            "tests": [t.to_json_dict() for t in self.tests],
            "pinned": list(self.pinned),
        }


def holm(p_values: Sequence[float], level: float) -> tuple[list[bool], list[float]]:
    """Holm's step-down rejections of ``p_values`` at family-wise ``level``,
    and the level each p-value was compared with (in input order)."""
    m = len(p_values)
    order = sorted(range(m), key=lambda i: p_values[i])
    rejected = [False] * m
    levels = [level / m] * m if m else []
    going = True
    for rank, i in enumerate(order):
        levels[i] = level / (m - rank)
        if going and p_values[i] <= levels[i]:
            rejected[i] = True
        else:
            going = False
    return rejected, levels


class _Linear:
    """Variances of linear combinations of the residuals on one axis."""

    def __init__(
        self,
        variances: FloatArray,
        loadings: FloatArray | None,
        parameter_cov: FloatArray | None,
        sign: float,
    ) -> None:
        self.variances = variances  # (n, 3)
        self.loadings = loadings  # (n, 3, p)
        self.parameter_cov = parameter_cov
        self.sign = sign

    def variance(self, c: FloatArray, axis: int) -> tuple[float, float]:
        """(variance with the parameter term, without it) of sum c_i r_i[axis]."""
        plain = float(np.sum(c**2 * self.variances[:, axis]))
        if self.loadings is None or self.parameter_cov is None:
            return plain, plain
        g = c @ self.loadings[:, axis, :]
        return plain + self.sign * float(g @ self.parameter_cov @ g), plain


def _z_test(
    kind: Kind,
    group: str,
    axis: int,
    n: int,
    value: float,
    variances: tuple[float, float],
    turns: bool = False,
) -> BiasTest | None:
    var, plain = variances
    if not (plain > 0 and var > PINNED_FRACTION * plain):
        return None
    se = math.sqrt(var)
    z = value / se
    p = 2.0 * distributions.norm_cdf(-abs(z))
    return BiasTest(kind, group, AXES[axis], n, value, se, z, p, turns=turns)


def _groups(labels: Sequence[TrialLabel]) -> list[tuple[str, FloatArray]]:
    """(name, member mask) of each tested group, finest first, duplicates dropped."""
    n = len(labels)
    candidates: list[tuple[str, list[bool]]] = []
    for name in dict.fromkeys(label.cell for label in labels):
        candidates.append((name, [label.cell == name for label in labels]))
    directions = dict.fromkeys(label.direction for label in labels)
    for d in directions:
        if d != "mixed":
            candidates.append((d, [label.direction == d for label in labels]))
    for f in dict.fromkeys(label.family for label in labels):
        candidates.append((f, [label.family == f for label in labels]))
    candidates.append(("all", [True] * n))
    seen: set[tuple[bool, ...]] = set()
    out = []
    for name, mask in candidates:
        key = tuple(mask)
        if key in seen or sum(mask) < MIN_GROUP:
            continue
        seen.add(key)
        out.append((name, np.array(mask, dtype=bool)))
    return out


def _spread_test(
    residuals: FloatArray, variances: FloatArray, labels: Sequence[TrialLabel], axis: int
) -> BiasTest | None:
    cells = list(dict.fromkeys(label.cell for label in labels))
    n = len(labels)
    g = len(cells)
    if g < 2 or n - g < 2:
        return None
    r = residuals[:, axis]
    w = 1.0 / variances[:, axis]
    overall = float(np.sum(w * r) / np.sum(w))
    between = 0.0
    within = 0.0
    best: tuple[float, str, float, int, float, bool] = (-1.0, "", 0.0, 0, 0.0, False)
    for cell in cells:
        mask = np.array([label.cell == cell for label in labels])
        turns = any(label.turns for label in labels if label.cell == cell)
        wg = w[mask]
        mean = float(np.sum(wg * r[mask]) / np.sum(wg))
        between += float(np.sum(wg)) * (mean - overall) ** 2
        within += float(np.sum(wg * (r[mask] - mean) ** 2))
        se = 1.0 / math.sqrt(float(np.sum(wg)))
        z = mean / se
        if abs(z) > best[0]:
            best = (abs(z), cell, mean, int(mask.sum()), se, turns)
    if within <= 0:
        return None
    f = (between / (g - 1)) / (within / (n - g))
    p = distributions.f_sf(f, g - 1, n - g)
    _, cell, mean, count, se, turns = best
    axis_name = "heading" if AXES[axis] == "theta" else AXES[axis]
    size = _signed_text(AXES[axis], mean)
    detail = (
        f"most on the {units.plural(count, cell + ' trial')}: {axis_name} {size}; "
        f"{g - 1} and {n - g} dof"
    )
    return BiasTest("spread", "groups", AXES[axis], g, mean, se, f, p, detail=detail, turns=turns)


_MIRRORS = {"cw": (1.0, -1.0, -1.0), "backward": (-1.0, 1.0, -1.0)}
"""Per direction, the signs that mirror a residual onto the other direction's
frame (a clockwise path is the mirror image (x, -y, -heading) of a
counter-clockwise one; a backward path (-x, y, -heading) of a forward one)."""


def _order_tests(
    residuals: FloatArray, labels: Sequence[TrialLabel], linear: _Linear
) -> list[BiasTest]:
    """First trial minus the rest of its run, pooled over the runs with
    inverse-variance weights; clockwise and backward runs mirrored onto the
    counter-clockwise and forward frame first, so that an effect in the sense
    of travel (the first run of a session turning short in either direction)
    adds up instead of cancelling."""
    runs: dict[tuple[str, str, str], list[int]] = {}
    for i, label in enumerate(labels):
        runs.setdefault(label.order_key, []).append(i)
    runs = {k: v for k, v in runs.items() if len(v) >= 2}
    if len(runs) < 1:
        return []
    n = len(labels)
    signs = np.array([_MIRRORS.get(label.direction, (1.0, 1.0, 1.0)) for label in labels])
    described = (
        "each session and direction" if any(label.run for label in labels) else ("each group")
    )
    if any(label.direction in _MIRRORS for label in labels):
        described += "; cw and backward runs mirrored"
    out = []
    for axis in range(3):
        contrasts = []
        weights = []
        for members in runs.values():
            c = np.zeros(n)
            c[members[0]] = 1.0
            c[members[1:]] = -1.0 / (len(members) - 1)
            c = c * signs[:, axis]
            var, _ = linear.variance(c, axis)
            if var <= 0:
                continue
            contrasts.append(c)
            weights.append(1.0 / var)
        if not contrasts:
            continue
        total = np.sum([w * c for w, c in zip(weights, contrasts, strict=True)], axis=0) / sum(
            weights
        )
        value = float(total @ residuals[:, axis])
        test = _z_test(
            "order", described, axis, len(contrasts), value, linear.variance(total, axis)
        )
        if test is not None:
            out.append(test)
    return out


def misfit_check(
    residuals: FloatArray,
    covariances: FloatArray,
    labels: Sequence[TrialLabel],
    jacobians: FloatArray | None = None,
    parameter_cov: FloatArray | None = None,
    *,
    fitted: bool = True,
    level: float = MISFIT_LEVEL,
    turn_hint: str = "",
) -> MisfitCheck:
    """The misfit tests of a set of residuals (see the module docstring).

    Args:
        residuals: (n, 3) measured minus predicted mean, x m, y m, heading rad
            (wrapped to (-pi, pi]).
        covariances: (n, 3, 3) predicted covariance of each residual (the
            model's plus the measurement's), SI.
        labels: each trial's groups.
        jacobians: (n, 3, p) derivative of each predicted mean in the
            parameters, or None (the parameters' uncertainty left out).
        parameter_cov: (p, p) the estimate's covariance (SI), or None.
        fitted: residuals of the trials the parameters were fitted on (the fit
            pulls them in) rather than held-out trials.
        level: the family-wise level.
        turn_hint: advice added to a bias on trials that turn.

    Raises:
        ParameterError: shapes disagree, non-finite input or a level out of (0, 0.5].
    """
    residuals = np.asarray(residuals, dtype=np.float64)
    n = len(labels)
    if residuals.shape != (n, 3) or not np.all(np.isfinite(residuals)):
        raise ParameterError(f"residuals must be finite, shape ({n}, 3), got {residuals.shape}")
    covariances = np.asarray(covariances, dtype=np.float64)
    if covariances.shape != (n, 3, 3) or not np.all(np.isfinite(covariances)):
        raise ParameterError(f"covariances must be finite, shape ({n}, 3, 3)")
    if not (math.isfinite(level) and 0.0 < level <= 0.5):
        raise ParameterError(f"the level must be in (0, 0.5], got {level!r}")
    variances = np.einsum("nii->ni", covariances).copy()
    loadings = None
    cov = None
    if jacobians is not None and parameter_cov is not None:
        loadings = np.asarray(jacobians, dtype=np.float64)
        cov = np.asarray(parameter_cov, dtype=np.float64)
        p = cov.shape[0]
        if loadings.shape != (n, 3, p) or cov.shape != (p, p):
            raise ParameterError(
                f"jacobians must have shape ({n}, 3, p) and the parameter covariance (p, p)"
            )
        if not (np.all(np.isfinite(loadings)) and np.all(np.isfinite(cov))):
            loadings, cov = None, None  # a parameter without information: leave it out
    linear = _Linear(variances, loadings, cov, -1.0 if fitted else 1.0)
    tests: list[BiasTest] = []
    pinned: list[str] = []
    for name, mask in _groups(labels):
        c = mask / mask.sum()
        turns = any(label.turns for label, member in zip(labels, mask, strict=True) if member)
        for axis in range(3):
            test = _z_test(
                "group",
                name,
                axis,
                int(mask.sum()),
                float(c @ residuals[:, axis]),
                linear.variance(c, axis),
                turns,
            )
            if test is None:
                pinned.append(f"{name} {AXES[axis]}")
            else:
                tests.append(test)
    if fitted:
        for axis in range(3):
            spread = _spread_test(residuals, variances, labels, axis)
            if spread is not None:
                tests.append(spread)
    tests += _order_tests(residuals, labels, linear)
    rejected, levels = holm([t.p_value for t in tests], level)
    done = tuple(
        BiasTest(
            t.kind,
            t.group,
            t.axis,
            t.n,
            t.bias,
            t.stderr,
            t.statistic,
            t.p_value,
            lv,
            r,
            t.detail,
            t.turns,
        )
        for t, r, lv in zip(tests, rejected, levels, strict=True)
    )
    return MisfitCheck(
        passed=not any(rejected),
        level=level,
        fitted=fitted,
        tests=done,
        pinned=tuple(pinned),
        turn_hint=turn_hint,
    )


class Prediction(Protocol):
    """A model's prediction of one trial (e.g.
    :class:`odohil.science.validation.PathPrediction`), SI."""

    @property
    def mean(self) -> FloatArray:
        """(3,) expected (x m, y m, heading rad minus the path's winding)."""
        ...

    @property
    def cov(self) -> FloatArray:
        """(3, 3) the model's covariance (without the measurement's)."""
        ...

    @property
    def jacobian(self) -> FloatArray:
        """(3, p) d mean / d parameters."""
        ...


def labels_of(trials: Sequence[PathTrial]) -> list[TrialLabel]:
    """The groups of general-path trials: their family and direction; the run
    (for the trial-order check) is their source, or the source's folder when
    every source holds one trial (a data set of one file per run, a folder per
    session, as the optiodom data set); a trial turns when its turns add up to
    :data:`TURNING_RAD` or more."""
    per_source: dict[str, int] = {}
    for trial in trials:
        per_source[trial.source] = per_source.get(trial.source, 0) + 1
    one_each = all(count == 1 for count in per_source.values())
    out = []
    for trial in trials:
        run = _folder(trial.source) if one_each else trial.source
        turned = sum(abs(s.angle_rad) for s in trial.path.steps if isinstance(s, Turn))
        turns = turned >= TURNING_RAD
        out.append(TrialLabel(trial.family, trial.direction, run, turns))
    return out


def _folder(source: str) -> str:
    """The folder part of a file name (``/`` or ``\\`` separated), else the name."""
    cut = max(source.rfind("/"), source.rfind("\\"))
    return source[:cut] if cut > 0 else source


def path_misfit(
    trials: Sequence[PathTrial],
    predictions: Sequence[Prediction],
    parameter_cov: FloatArray | None,
    *,
    fitted: bool = True,
    level: float = MISFIT_LEVEL,
    turn_hint: str = "",
) -> MisfitCheck:
    """:func:`misfit_check` of general-path trials against a model's
    per-trial predictions (any model: the four parameters, or with turn errors;
    ``parameter_cov`` is the covariance of the parameters the Jacobians are
    taken in, SI)."""
    if len(predictions) != len(trials):
        raise ParameterError(
            f"{units.plural(len(trials), 'trial')} but {len(predictions)} predictions"
        )
    n = len(trials)
    residuals = np.empty((n, 3))
    covs = np.empty((n, 3, 3))
    for i, (trial, prediction) in enumerate(zip(trials, predictions, strict=True)):
        r = trial.pose_change - prediction.mean
        r[2] = wrap_angle(float(r[2]))
        residuals[i] = r
        covs[i] = prediction.cov + trial.measurement_cov
    jacobians = np.stack([np.asarray(p.jacobian, dtype=np.float64) for p in predictions])
    return misfit_check(
        residuals,
        covs,
        labels_of(trials),
        jacobians,
        parameter_cov,
        fitted=fitted,
        level=level,
        turn_hint=turn_hint,
    )
