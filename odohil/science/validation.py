"""Does the calibrated model predict a path it was not fitted on?

Validation trials of known encoder paths (forth-and-back designs, squares, any
:class:`~odohil.science.paths.EncoderPath`) are tested against the model's
prediction at the estimated parameters:

- trial i's pose change p_i = (x m, y m, Delta rad) is predicted with mean
  m_i = E[p | theta-hat] and covariance S_i = C_i(theta-hat) + R_i, the model's
  exact covariance (:func:`~odohil.science.moments.pose_moments`) plus the
  measurement covariance R_i of the measured pose;
- the estimate's own uncertainty (covariance Sigma of theta-hat, 4 x 4, SI)
  enters by the delta method through the mean: m_i moves by J_i e with
  J_i = d m_i / d theta (3 x 4, central differences) and e ~ N(0, Sigma). The
  error e is the same for every trial, so the trials are not independent:
  the stacked residual r = (r_1, ..., r_n) has covariance
  V = blockdiag(S_i) + J Sigma J^T, J the stacked J_i;
- the statistic is the normalised estimation error squared over the whole
  set, NEES = r^T V^-1 r, chi-square with 3n degrees of freedom when the
  model is right; per axis a (x, y, theta) the same with the n residuals of
  that axis (dof n). V^-1 is applied by the Woodbury identity with
  Sigma = L L^T, so the cost is O(n).

The NEES test is one-sided (upper tail): a NEES too large means the robot
strays further than the model says, which is what "confidently wrong" means; a
NEES too small only means the model is cautious.

The NEES is blind to a bias the trials share when the predicted spread is too
large (issue 20: calibrated on straight runs and clockwise circles, whose
turn-scale error the fit absorbed into K_theta, 16 counter-clockwise circles
gave NEES 29.2 on 48 dof, "pass", while their mean heading residual was
+2.49 deg against a predicted per-trial SD of 1.14 deg: a bias of 3n/48 of the
statistic is lost among the other dof). So the **mean residual** is tested
too: r-bar = (1/n) sum r_i has covariance W = (1/n^2) (sum S_i + (sum J_i)
Sigma (sum J_i)^T) (the parameter error is shared, so it does not average
out); overall r-bar^T W^-1 r-bar is chi-square(3), per axis r-bar_a^2 / W_aa
chi-square(1) (two-sided z).

Eight tests (NEES and bias, each overall, x, y, theta) each at level alpha/8
(Bonferroni): the set fails when any one rejects, so the false-rejection rate
of the verdict is at most alpha.

**What a pass rules out** (:class:`Detectable`): a true parameter Delta_j away
from the estimate moves every trial's mean by J_i e_j Delta_j, so the mean
residual by J-bar_j Delta_j (J-bar the trials' mean Jacobian) while W stays
the same. The overall bias test then has noncentrality Delta_j^2 J-bar_j^T
W^-1 J-bar_j (chi-square(3)), the axis-a test Delta_j^2 J-bar_aj^2 / W_aa
(chi-square(1)). The smallest |Delta_j| that one of them rejects with
probability ``power`` bounds what the verdict misses: it rejects whenever any
test does, so it catches that error at least as often. A validation of few or
noisy trials passes errors a user would call large; the number says how large.

**The spread's own uncertainty** (issue 31). The predicted spread S_i =
C_i(theta-hat) + R_i is an estimate too: an error e of the variance rates
scales it, S_i(theta-hat) = S_i(theta) (1 + g^T e) to first order
(:func:`nees_scale_dofs`), so a NEES given the calibration is chi-square
times the ratio of the true spread to the predicted one. That ratio is not a
normal variable around 1: a variance estimated from nu squares is chi^2(nu) /
nu times the truth, and its reciprocal has a heavy upper tail (a K_rho that
came out at half the truth doubles every x and y NEES). With the relative
error's SD s = sqrt(g^T Sigma g) (Sigma the Wald covariance at the estimate:
s does not shrink with a low estimate, the relative SE of a variance rate
being about sqrt(2 / nu) whatever its value) the spread has nu = 2 / s^2
degrees of freedom (Satterthwaite), and NEES / dof is F(dof, nu): the exact
law when the spread is one variance estimated from nu squares, independent
of the validation trials. The bias tests' W = A + B likewise
(:func:`bias_scale_dofs`): A = sum S_i / n^2 carries the spread's error, B =
J-bar Sigma J-bar^T the error of Sigma itself (the calibration's
Satterthwaite degrees of freedom of each SE^2, ``parameter_dofs``); both
follow the variance rates, so their errors are added as fully correlated
(conservative), and z^2 is F(1, nu_W) (a Student t), the overall r-bar^T
W^-1 r-bar / 3 F(3, nu_W). A normal scale mixture (1 + s z) chi-square with
the same variance (the previous rule) has a light tail: at s = 0.3, 15
trials, it rejected a calibrated robot's x NEES at 0.0067 where the level was
0.00125 (tests/science/test_validation_level.py; BENCHMARKS.md, "Validation
sized by power").

What the first-order rule leaves out: the spread's dependence on the
estimate beyond the linear term, and the NEES tests' share of B's error (B
spans at most q of the 3n directions). With many validation trials the test
becomes a test of K_theta and K_rho themselves, at the calibration's own
precision: nu bounds how small a spread error any number of trials can
tell from the calibration's. docs/validation.md says how many trials keep the
test honest.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from odohil.errors import ParameterError
from odohil.science import distributions
from odohil.science.moments import pose_moments, turn_errors_from
from odohil.science.parameters import ErrorParameters
from odohil.science.paths import EncoderPath, FloatArray
from odohil.units import wrap_angles

AXES = ("x", "y", "theta")
"""The pose-change components, in order: x m, y m, Delta rad."""
DEFAULT_ALPHA = 0.01
"""Default false-rejection level of the whole verdict."""
N_TESTS = 8
"""NEES and bias, each overall plus one per axis; each run at alpha / N_TESTS
(Bonferroni)."""

DETECTION_POWER = 0.9
"""The probability with which :attr:`ValidationResult.detectable` errors are caught."""

_RELATIVE_STEP = 1e-4
_ABSOLUTE_STEPS = (1e-7, 1e-7, 1e-10, 1e-10)
"""Smallest central-difference steps per parameter (E_R rad/m, E_T, K_theta
rad^2/m, K_rho m): the mean is smooth in each."""


@dataclass(frozen=True)
class PathPrediction:
    """The model's prediction of one trial of a path, SI.

    Attributes:
        mean: (3,) expected (x m, y m, Delta rad).
        cov: (3, 3) the model's covariance (without measurement noise).
        jacobian: (3, 4) d mean / d (E_R, E_T, K_theta, K_rho) (or (3, q): a
            general-path fit's parameters).
        cov_jacobian: (3, 3, q) d cov / d the same parameters, or None (then
            the NEES tests leave the spread's dependence on the estimate out).
    """

    mean: FloatArray
    cov: FloatArray
    jacobian: FloatArray
    cov_jacobian: FloatArray | None = None


def predict_path(path: EncoderPath, params: ErrorParameters) -> PathPrediction:
    """Mean, covariance and the mean's Jacobian in the parameters of one trial."""
    moments = pose_moments(path, params)
    values = np.array(params.as_tuple(), dtype=np.float64)
    jacobian = np.zeros((3, 4))
    cov_jacobian = np.zeros((3, 3, 4))
    for j in range(4):
        step = max(_ABSOLUTE_STEPS[j], _RELATIVE_STEP * abs(values[j]))
        low, high = values.copy(), values.copy()
        high[j] += step
        low[j] -= step
        if j >= 2 and low[j] < 0:  # variance rates stay >= 0: one-sided difference
            low[j] = values[j]
        width = high[j] - low[j]
        up = pose_moments(path, ErrorParameters(*high))
        down = pose_moments(path, ErrorParameters(*low))
        jacobian[:, j] = (up.mean - down.mean) / width
        cov_jacobian[:, :, j] = (up.cov - down.cov) / width
    return PathPrediction(moments.mean, moments.cov, jacobian, cov_jacobian)


def predict_fitted(
    path: EncoderPath, names: Sequence[str], values: Sequence[float]
) -> PathPrediction:
    """:func:`predict_path` at a general-path fit's parameters (``names`` and
    SI ``values`` in the order of its ``parameters``: the four, then e_turn...
    and K_spin, odohil/science/estimators/paths.py): the turn errors enter the
    mean and covariance, and the Jacobian is (3, q), one column per parameter."""
    v = np.array(values, dtype=np.float64)
    rates = [j for j, name in enumerate(names) if name in ("K_theta", "K_rho", "K_spin")]

    def moments(at: FloatArray) -> tuple[FloatArray, FloatArray]:
        turns = turn_errors_from(names, [float(x) for x in at])
        m = pose_moments(path, ErrorParameters(*at[:4]), None if turns.exact else turns)
        return m.mean, m.cov

    mean, cov = moments(v)
    jacobian = np.zeros((3, len(v)))
    cov_jacobian = np.zeros((3, 3, len(v)))
    for j in range(len(v)):
        floor = _ABSOLUTE_STEPS[j] if j < 4 else 1e-7
        step = max(floor, _RELATIVE_STEP * abs(v[j]))
        low, high = v.copy(), v.copy()
        high[j] += step
        low[j] -= step
        if j in rates and low[j] < 0:  # variance rates stay >= 0: one-sided difference
            low[j] = v[j]
        (up_mean, up_cov), (down_mean, down_cov) = moments(high), moments(low)
        jacobian[:, j] = (up_mean - down_mean) / (high[j] - low[j])
        cov_jacobian[:, :, j] = (up_cov - down_cov) / (high[j] - low[j])
    return PathPrediction(mean, cov, jacobian, cov_jacobian)


@dataclass(frozen=True)
class ChiSquareTest:
    """One upper-tail chi-square test.

    Attributes:
        name: ``overall``, ``x``, ``y`` or ``theta`` (the NEES tests);
            ``bias``, ``bias x``, ``bias y``, ``bias theta`` (the mean residual).
        statistic: the NEES (squared Mahalanobis distance of the stacked
            residuals), or the mean residual's squared Mahalanobis distance.
        dof: degrees of freedom (NEES: 3n overall, n per axis; bias: 3, 1).
        p_value: chi-square(dof) upper-tail probability of ``statistic``.
        level: the level it is run at (alpha / 8).
        threshold: the statistic above which it rejects (the 1 - level quantile).
        passed: statistic <= threshold.
        mean: bias tests: the mean residual (x m, y m, heading rad), or its axis.
        stderr: bias tests: its predicted standard error, per component.
    """

    name: str
    statistic: float
    dof: int
    p_value: float
    level: float
    threshold: float
    passed: bool
    mean: tuple[float, ...] = ()
    stderr: tuple[float, ...] = ()

    @property
    def is_bias(self) -> bool:
        """Whether this tests the mean residual (else the NEES)."""
        return bool(self.mean)

    def describe(self) -> str:
        """For people: ``heading mean residual +2.49 deg (SE 0.41 deg, z = 6.1)``."""
        if not self.is_bias:
            return f"{self.name} NEES {self.statistic:.4g} on {self.dof} dof"
        parts = []
        axes = AXES if len(self.mean) == 3 else (self.name.split()[-1],)
        for axis, m, se in zip(axes, self.mean, self.stderr, strict=True):
            if axis == "theta":
                parts.append(
                    f"heading mean residual {math.degrees(m):+.2f} deg "
                    f"(SE {math.degrees(se):.2g} deg, z = {m / se:.1f})"
                )
            else:
                parts.append(
                    f"{axis} mean residual {1e3 * m:+.3g} mm (SE {1e3 * se:.2g} mm, "
                    f"z = {m / se:.1f})"
                )
        return "; ".join(parts)

    def to_json_dict(self) -> dict[str, Any]:
        """NEES: {"nees", "dof", "p_value", "level", "threshold", "passed"};
        bias: {"statistic", "mean", "stderr", "dof", ...} (SI)."""
        out: dict[str, Any] = {
            "dof": self.dof,
            "p_value": self.p_value,
            "level": self.level,
            "threshold": self.threshold,
            "passed": self.passed,
        }
        if self.is_bias:
            out["statistic"] = self.statistic
            out["mean"] = list(self.mean)
            out["stderr"] = list(self.stderr)
        else:
            out["nees"] = self.statistic
        return out


@dataclass(frozen=True)
class Detectable:
    """The smallest error of one parameter the bias tests catch (module docs).

    Attributes:
        index: the parameter's column in the predictions' Jacobians (E_R, E_T,
            K_theta, K_rho, then a general-path fit's turn errors).
        shift: the smallest |true - estimated| value, in the parameter's SI
            unit, that ``test`` rejects with probability ``power`` (math.inf
            when the predicted mean does not move with the parameter).
        test: the bias test that catches it first (``bias``, ``bias x``, ...).
        power: the probability of catching it.
    """

    index: int
    shift: float
    test: str
    power: float


@dataclass(frozen=True)
class ValidationResult:
    """The NEES and bias tests of one validation set.

    Attributes:
        passed: no test rejects.
        alpha: the verdict's false-rejection level (each test at alpha / 8).
        n_trials: trials tested.
        overall: the joint NEES test of all 3n residuals.
        axes: the per-axis NEES tests, x, y, theta.
        residuals: (n, 3) measured minus predicted mean (heading wrapped to
            (-pi, pi]).
        trial_nees: (n,) each trial's own squared distance r_i^T V_ii^-1 r_i
            (chi-square(3) alone; for pointing at a trial, not for the verdict).
        parameter_uncertainty: whether the estimate's covariance was included.
        bias: the mean-residual tests: overall (chi-square(3)), then x, y,
            theta (chi-square(1), i.e. two-sided z).
        detectable: per parameter (Jacobian column), the smallest error the
            bias tests catch with probability :data:`DETECTION_POWER`.
    """

    passed: bool
    alpha: float
    n_trials: int
    overall: ChiSquareTest
    axes: tuple[ChiSquareTest, ...]
    residuals: FloatArray
    trial_nees: FloatArray
    parameter_uncertainty: bool
    bias: tuple[ChiSquareTest, ...] = ()
    detectable: tuple[Detectable, ...] = ()

    @property
    def level(self) -> float:
        """The level each test is run at (Bonferroni over the tests)."""
        return self.overall.level

    @property
    def tests(self) -> tuple[ChiSquareTest, ...]:
        """The NEES tests (overall, x, y, theta), then the bias tests (same order)."""
        return (self.overall, *self.axes, *self.bias)

    def reasons(self) -> tuple[str, ...]:
        """One sentence per failed kind: which tests, and for a bias its size."""
        out = []
        spread = [t for t in (self.overall, *self.axes) if not t.passed]
        if spread:
            out.append(
                "spread (NEES) larger than predicted: " + ", ".join(t.describe() for t in spread)
            )
        bias = [t for t in self.bias if not t.passed]
        if bias:
            axes = [t for t in bias if t.dof == 1] or bias
            out.append("a bias the trials share: " + "; ".join(t.describe() for t in axes))
        return tuple(out)

    def failed(self) -> tuple[str, ...]:
        """Names of the tests that reject."""
        return tuple(t.name for t in self.tests if not t.passed)

    def to_json_dict(self) -> dict[str, Any]:
        """{"status", "alpha", "n_trials", "overall", "axes", "failed",
        "reasons", "bias": {"overall", "axes"}, "parameter_uncertainty",
        "trial_nees"} (SI)."""
        return {
            "status": "pass" if self.passed else "fail",
            "alpha": self.alpha,
            "n_trials": self.n_trials,
            "overall": self.overall.to_json_dict(),
            "axes": {t.name: t.to_json_dict() for t in self.axes},
            "failed": list(self.failed()),
            "reasons": list(self.reasons()),
            "bias": {
                "overall": self.bias[0].to_json_dict(),
                "axes": {t.name.split()[-1]: t.to_json_dict() for t in self.bias[1:]},
            }
            if self.bias
            else None,
            "parameter_uncertainty": self.parameter_uncertainty,
            "trial_nees": [float(v) for v in self.trial_nees],
        }


def _sqrt_psd(matrix: FloatArray) -> FloatArray:
    """L with L L^T = matrix (symmetric PSD; tiny negative eigenvalues clipped)."""
    sym = 0.5 * (matrix + matrix.T)
    values, vectors = np.linalg.eigh(sym)
    root: FloatArray = vectors * np.sqrt(np.clip(values, 0.0, None))
    return root


def _woodbury_nees(
    residuals: FloatArray, blocks: FloatArray, loadings: FloatArray
) -> tuple[float, FloatArray]:
    """r^T (blockdiag(S_i) + U U^T)^-1 r for r = (r_1..r_n), U = (U_1; ..; U_n).

    residuals (n, d), blocks (n, d, d) positive definite, loadings (n, d, q).
    Also returns each r_i^T (S_i + U_i U_i^T)^-1 r_i.
    """
    try:
        chol = np.linalg.cholesky(blocks)
    except np.linalg.LinAlgError as exc:
        raise ParameterError(
            "a predicted covariance is not positive definite: the model predicts no "
            "spread on some axis and no measurement covariance was given"
        ) from exc
    white_r = np.linalg.solve(chol, residuals[..., None])[..., 0]  # L_i^-1 r_i
    white_u = np.linalg.solve(chol, loadings)  # L_i^-1 U_i
    plain = float(np.sum(white_r**2))
    q = loadings.shape[2]
    b = np.einsum("nij,ni->j", white_u, white_r)  # U^T D^-1 r
    inner = np.eye(q) + np.einsum("nij,nik->jk", white_u, white_u)  # I + U^T D^-1 U
    nees = plain - float(b @ np.linalg.solve(inner, b))
    full = blocks + np.einsum("nij,nkj->nik", loadings, loadings)
    per_trial = np.einsum(
        "ni,ni->n", residuals, np.linalg.solve(full, residuals[..., None])[..., 0]
    )
    return nees, per_trial


SCALE_DOF_MAX = 1e6
"""A spread known to about 0.1 %: tested against the chi-square itself."""


def scale_dof(relative_sd: float) -> float:
    """The degrees of freedom of a predicted variance uncertain by the relative
    standard deviation ``relative_sd`` (Satterthwaite: a variance estimated
    from nu squares has relative SD sqrt(2 / nu)); inf for an exact one."""
    if not relative_sd > 0:
        return math.inf
    nu = 2.0 / float(relative_sd) ** 2
    return math.inf if nu > SCALE_DOF_MAX else max(nu, 1.0)


def _test(
    name: str,
    statistic: float,
    dof: int,
    level: float,
    mean: tuple[float, ...] = (),
    stderr: tuple[float, ...] = (),
    spread_dof: float = math.inf,
) -> ChiSquareTest:
    """One test; a statistic whose predicted variance is itself an estimate of
    ``spread_dof`` degrees of freedom (:func:`scale_dof`) against dof F(dof,
    spread_dof) (module docstring, "The spread's own uncertainty")."""
    threshold = float(distributions.chi2_estimated_scale_isf(level, dof, float(spread_dof)))
    return ChiSquareTest(
        name=name,
        statistic=statistic,
        dof=dof,
        p_value=float(distributions.chi2_estimated_scale_sf(statistic, dof, float(spread_dof))),
        level=level,
        threshold=threshold,
        passed=bool(statistic <= threshold),
        mean=mean,
        stderr=stderr,
    )


def nees_scale_dofs(
    d_cov: FloatArray | None, blocks: FloatArray, parameter_cov: FloatArray | None
) -> tuple[float, ...]:
    """The degrees of freedom of the predicted spread each NEES test (overall,
    x, y, theta) divides by, from the estimate's uncertainty (module
    docstring, "The spread's own uncertainty"): the spread's relative error
    given the estimate's error e is g^T e, g_j the mean over trials of
    tr(S_i^-1 dC_i/d theta_j) / 3 (overall) or (dC_i/d theta_j)_aa / S_i,aa
    (axis a); returns :func:`scale_dof` of sqrt(g^T Sigma g) per test (inf
    without the covariance's Jacobian ``d_cov`` (n, 3, 3, q) or the estimate's
    covariance)."""
    if parameter_cov is None or d_cov is None:
        return (math.inf,) * 4
    whitened = np.linalg.solve(blocks[:, None, :, :], np.moveaxis(d_cov, 3, 1))  # (n, q, 3, 3)
    rows = [np.trace(whitened, axis1=2, axis2=3).mean(axis=0) / 3.0]
    diagonal = np.diagonal(blocks, axis1=1, axis2=2)  # (n, 3)
    rows += [(d_cov[:, a, a, :] / diagonal[:, a : a + 1]).mean(axis=0) for a in range(3)]
    sigma = np.asarray(parameter_cov, dtype=np.float64)
    return tuple(scale_dof(math.sqrt(max(float(g @ sigma @ g), 0.0))) for g in rows)


def bias_scale_dofs(
    bias_cov: FloatArray,
    d_spread: FloatArray | None,
    mean_jacobian: FloatArray,
    parameter_cov: FloatArray | None,
    parameter_dofs: Sequence[float] | None,
) -> tuple[float, ...]:
    """The degrees of freedom of W, the mean residual's predicted covariance,
    for each bias test (overall, x, y, theta; module docstring). W = A + B,
    A = sum S_i / n^2 the trials' spread, B = J-bar Sigma J-bar^T the
    estimate's. A's error is dA e (``d_spread`` (3, 3, q): sum dC_i / n^2);
    B's is Sigma's own, each SE^2 uncertain by sqrt(2 / nu_j) (``parameter_dofs``,
    the calibration's degrees of freedom, inf when known), taken as fully
    correlated, as are A's and B's errors (both follow the variance rates):
    the relative SD of W_aa (or of tr(W^-1 W) / 3) is (sd_A + sd_B) / W."""
    if parameter_cov is None:
        return (math.inf,) * 4
    sigma = np.asarray(parameter_cov, dtype=np.float64)
    q = sigma.shape[0]
    rel = np.zeros(q)
    if parameter_dofs is not None:
        rel = np.array([math.sqrt(2.0 / v) if v > 0 and math.isfinite(v) else 0.0
                        for v in parameter_dofs])  # fmt: skip
    scaled = sigma * 0.5 * (rel[:, None] + rel[None, :])
    d_b = mean_jacobian @ scaled @ mean_jacobian.T  # B's error per unit z
    w_inv = np.linalg.inv(bias_cov)
    d_a = np.zeros((3, 3, q)) if d_spread is None else d_spread
    h = [np.einsum("ij,jik->k", w_inv, d_a) / 3.0]
    h += [d_a[a, a, :] / bias_cov[a, a] for a in range(3)]
    spread_b = [abs(float(np.trace(w_inv @ d_b))) / 3.0]
    spread_b += [abs(float(d_b[a, a])) / bias_cov[a, a] for a in range(3)]
    return tuple(
        scale_dof(math.sqrt(max(float(g @ sigma @ g), 0.0)) + b)
        for g, b in zip(h, spread_b, strict=True)
    )


def _bias_tests(
    residuals: FloatArray, cov: FloatArray, level: float, spread_dofs: Sequence[float]
) -> list[ChiSquareTest]:
    """The mean residual's tests (module docstring): overall, then per axis;
    ``cov`` is W, the mean residual's predicted covariance, ``spread_dofs``
    its degrees of freedom per test (:func:`bias_scale_dofs`)."""
    mean = residuals.mean(axis=0)
    se = np.sqrt(np.diag(cov))
    try:
        overall = float(mean @ np.linalg.solve(cov, mean))
    except np.linalg.LinAlgError as exc:
        raise ParameterError("the mean residual's predicted covariance is singular") from exc
    values = tuple(float(v) for v in mean)
    errors = tuple(float(v) for v in se)
    tests = [_test("bias", overall, 3, level, values, errors, spread_dofs[0])]
    for a, name in enumerate(AXES):
        z2 = float(mean[a] ** 2 / cov[a, a])
        tests.append(
            _test(f"bias {name}", z2, 1, level, (values[a],), (errors[a],), spread_dofs[a + 1])
        )
    return tests


def _bias_covariance(blocks: FloatArray, loadings: FloatArray) -> FloatArray:
    """W, the mean residual's predicted covariance (module docstring)."""
    n = blocks.shape[0]
    shared = loadings.sum(axis=0)  # (3, q): sum J_i L
    cov: FloatArray = (blocks.sum(axis=0) + shared @ shared.T) / n**2
    return cov


def detectable_errors(
    mean_jacobian: FloatArray, bias_cov: FloatArray, level: float, power: float = DETECTION_POWER
) -> tuple[Detectable, ...]:
    """Per parameter, the smallest error the bias tests (each at ``level``)
    catch with probability ``power`` (module docstring, "What a pass rules out").

    Args:
        mean_jacobian: (3, q) the trials' mean d mean / d parameters (SI).
        bias_cov: (3, 3) W, the mean residual's predicted covariance.
        level: each test's level (alpha / 8).
        power: the probability of catching the error, in (level, 1).
    """
    if not (level < power < 1.0):
        raise ParameterError(f"power must be in ({level:g}, 1), got {power!r}")
    w_inv = np.linalg.inv(bias_cov)
    needed_overall = distributions.ncx2_noncentrality(
        distributions.chi2_isf(level, 3), 3, 1.0 - power
    )
    needed_axis = distributions.ncx2_noncentrality(distributions.chi2_isf(level, 1), 1, 1.0 - power)
    out = []
    for j in range(mean_jacobian.shape[1]):
        a = mean_jacobian[:, j]
        # noncentrality per unit error squared: overall, then each axis
        per_unit = [("bias", float(a @ w_inv @ a), needed_overall)]
        per_unit += [
            (f"bias {name}", float(a[k] ** 2 / bias_cov[k, k]), needed_axis)
            for k, name in enumerate(AXES)
        ]
        shifts = [(math.sqrt(needed / unit), name) for name, unit, needed in per_unit if unit > 0.0]
        shift, test = min(shifts) if shifts else (math.inf, "")
        out.append(Detectable(index=j, shift=shift, test=test, power=power))
    return tuple(out)


def validation_test(
    poses: FloatArray,
    predictions: Sequence[PathPrediction],
    measurement_covs: FloatArray | None = None,
    parameter_cov: FloatArray | None = None,
    alpha: float = DEFAULT_ALPHA,
    parameter_dofs: Sequence[float] | None = None,
) -> ValidationResult:
    """Test measured pose changes against the model's predictions (module docs).

    Args:
        poses: (n, 3) measured (x m, y m, Delta rad), n >= 1.
        predictions: one per trial (trials of one path may share one).
        measurement_covs: (n, 3, 3) measurement covariances, or None (exact poses).
        parameter_cov: (q, q) covariance of the estimate (SI) in the parameters
            the predictions' (3, q) Jacobians are taken in (q = 4 for the four
            parameters, more with turn errors), or None to leave the parameter
            uncertainty out.
        alpha: the verdict's false-rejection level, in (0, 0.5].
        parameter_dofs: per parameter, the degrees of freedom of its variance
            in ``parameter_cov`` (the calibration's Satterthwaite nu; inf or
            None: known), for the bias tests' W (:func:`bias_scale_dofs`).

    Raises:
        ParameterError: shapes disagree, non-finite input, alpha out of range,
            or a predicted covariance is singular.
    """
    poses = np.asarray(poses, dtype=np.float64)
    n = poses.shape[0] if poses.ndim == 2 else 0
    if poses.ndim != 2 or poses.shape[1] != 3 or n < 1:
        raise ParameterError(f"poses must have shape (n, 3) with n >= 1, got {poses.shape}")
    if len(predictions) != n:
        raise ParameterError(f"{n} poses but {len(predictions)} predictions")
    if not (math.isfinite(alpha) and 0.0 < alpha <= 0.5):
        raise ParameterError(f"alpha must be in (0, 0.5], got {alpha!r}")
    if not np.all(np.isfinite(poses)):
        raise ParameterError("poses must be finite")
    means = np.stack([p.mean for p in predictions])
    blocks = np.stack([p.cov for p in predictions])
    jacobians = np.stack([p.jacobian for p in predictions])
    if measurement_covs is not None:
        measurement_covs = np.asarray(measurement_covs, dtype=np.float64)
        if measurement_covs.shape != (n, 3, 3) or not np.all(np.isfinite(measurement_covs)):
            raise ParameterError(
                f"measurement covariances must be finite, shape ({n}, 3, 3), "
                f"got {measurement_covs.shape}"
            )
        blocks = blocks + 0.5 * (measurement_covs + measurement_covs.transpose(0, 2, 1))
    if parameter_cov is not None:
        parameter_cov = np.asarray(parameter_cov, dtype=np.float64)
        q = jacobians.shape[2]
        if parameter_cov.shape != (q, q) or not np.all(np.isfinite(parameter_cov)):
            raise ParameterError(
                f"the estimate's covariance must be a finite {q} x {q} matrix, one row per "
                "parameter the predictions' Jacobians are taken in (a parameter the data do "
                "not determine has no finite covariance)"
            )
        loadings = jacobians @ _sqrt_psd(parameter_cov)
    else:
        loadings = np.zeros((n, 3, jacobians.shape[2]))
    residuals = poses - means
    residuals[:, 2] = wrap_angles(residuals[:, 2])
    level = alpha / N_TESTS
    derivatives = [p.cov_jacobian for p in predictions]
    d_cov = None
    if not any(d is None for d in derivatives):
        d_cov = np.stack([d for d in derivatives if d is not None])  # (n, 3, 3, q)
    if parameter_dofs is not None and len(parameter_dofs) != jacobians.shape[2]:
        raise ParameterError(
            f"{len(parameter_dofs)} degrees of freedom for {jacobians.shape[2]} parameters"
        )
    nees_dofs = nees_scale_dofs(d_cov, blocks, parameter_cov)
    overall, trial_nees = _woodbury_nees(residuals, blocks, loadings)
    tests = [_test("overall", overall, 3 * n, level, spread_dof=nees_dofs[0])]
    for a, name in enumerate(AXES):
        axis_nees, _ = _woodbury_nees(
            residuals[:, a : a + 1], blocks[:, a : a + 1, a : a + 1], loadings[:, a : a + 1, :]
        )
        tests.append(_test(name, axis_nees, n, level, spread_dof=nees_dofs[a + 1]))
    bias_cov = _bias_covariance(blocks, loadings)
    d_spread = None if d_cov is None else d_cov.sum(axis=0) / n**2
    bias_dofs = bias_scale_dofs(
        bias_cov, d_spread, jacobians.mean(axis=0), parameter_cov, parameter_dofs
    )
    bias = _bias_tests(residuals, bias_cov, level, bias_dofs)
    detectable = detectable_errors(jacobians.mean(axis=0), bias_cov, level)
    return ValidationResult(
        passed=all(t.passed for t in (*tests, *bias)),
        alpha=alpha,
        n_trials=n,
        overall=tests[0],
        axes=tuple(tests[1:]),
        residuals=residuals,
        trial_nees=trial_nees,
        parameter_uncertainty=parameter_cov is not None,
        bias=tuple(bias),
        detectable=detectable,
    )


@dataclass(frozen=True)
class EllipseData:
    """What a plot of validation trials against the prediction needs, SI.

    Attributes:
        mean: (2,) predicted mean end point (x m, y m).
        cov: (2, 2) predicted covariance of the end point (model + measurement
            + parameter terms of the first trial).
        points: (n, 2) measured end points (x m, y m).
        level: probability mass inside the ellipse drawn (e.g. 0.95).
        axes_m: the ellipse's semi-axes, metres (major first).
        angle_rad: direction of the major axis.
    """

    mean: FloatArray
    cov: FloatArray
    points: FloatArray
    level: float
    axes_m: tuple[float, float]
    angle_rad: float


def ellipse_data(
    poses: FloatArray,
    prediction: PathPrediction,
    measurement_cov: FloatArray | None = None,
    parameter_cov: FloatArray | None = None,
    level: float = 0.95,
) -> EllipseData:
    """The predicted end-point ellipse of one path (at probability ``level``)
    and the measured end points, for the report's plot."""
    cov = prediction.cov[:2, :2].copy()
    if measurement_cov is not None:
        cov = cov + np.asarray(measurement_cov, dtype=np.float64)[:2, :2]
    if parameter_cov is not None:
        j = prediction.jacobian[:2]
        cov = cov + j @ np.asarray(parameter_cov, dtype=np.float64) @ j.T
    values, vectors = np.linalg.eigh(0.5 * (cov + cov.T))
    scale = distributions.chi2_ppf(level, 2)
    major, minor = (math.sqrt(max(float(v), 0.0) * scale) for v in values[::-1])
    angle = math.atan2(float(vectors[1, -1]), float(vectors[0, -1]))
    return EllipseData(
        mean=prediction.mean[:2].copy(),
        cov=cov,
        points=np.asarray(poses, dtype=np.float64)[:, :2].copy(),
        level=level,
        axes_m=(major, minor),
        angle_rad=angle,
    )
