"""The result of an estimate: values, errors, intervals, and the two checks."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from odohil.science import distributions
from odohil.science.estimators.misfit import MisfitCheck
from odohil.science.estimators.verdict import TRUSTED, Verdict
from odohil.science.parameters import PARAMETER_NAMES, ErrorParameters, si_unit

VARIANCE_RATES = ("K_theta", "K_rho", "K_spin")
"""The parameters that are variance rates (positive, intervals in log K)."""
Z95 = 1.959963984540054
"""The 97.5 % quantile of the standard normal."""
_FOUR_SIGMA_UPPER = 0.9999683287581669
"""``norm_cdf(4.0)`` written out, so that importing this module computes nothing
with scipy (odohil/science/distributions.py; tests/science/test_distributions.py
checks it)."""


@dataclass(frozen=True)
class ParameterEstimate:
    """One parameter's estimate, SI.

    Attributes:
        name: E_R, E_T, K_theta or K_rho.
        value: the estimate.
        stderr: its Wald standard error: the square root of the diagonal of the
            inverse expected information at the estimate (inf when the data do
            not determine it). A scale, not the interval, for K_theta and K_rho.
        ci95: the 95 % interval. From :func:`odohil.science.estimators.estimate`
            (joint and robust methods): the Cox-Reid adjusted profile-likelihood
            interval for K_theta and K_rho, and estimate +- t quantile x stderr
            with Satterthwaite degrees of freedom for E_R and E_T
            (odohil/science/estimators/intervals.py). Otherwise (the paper
            method, the live estimate, :meth:`build`): symmetric for E_R and E_T;
            for K_theta and K_rho symmetric in log K (exp(log K +- q stderr/K)),
            or [0, q stderr] when the estimate is 0.
        unit: the SI unit.
        ci_4sigma: the same rule at the 4-sigma-equivalent level 99.9937 %
            (1 - 2 Phi(-4)): truth outside it is "confidently wrong".
        interval: how the intervals were formed, for people.
        dof: the t degrees of freedom of the intervals (None for a profile one).
    """

    name: str
    value: float
    stderr: float
    ci95: tuple[float, float]
    unit: str
    ci_4sigma: tuple[float, float] = (-math.inf, math.inf)
    interval: str = ""
    dof: float | None = None

    @classmethod
    def build(
        cls,
        name: str,
        value: float,
        stderr: float,
        quantile: float = Z95,
        dof: float | None = None,
    ) -> ParameterEstimate:
        """With the Wald rule above; ``quantile`` replaces 1.96 (e.g. a
        Student-t quantile at small n); ``dof``: the t degrees of freedom it
        came from (the 4-sigma-equivalent interval uses the t(dof) quantile of
        that level, else 4)."""
        wide_q = four_sigma_quantile(dof) if dof is not None else 4.0
        ci = _wald(name, value, stderr, quantile)
        wide = _wald(name, value, stderr, max(wide_q, quantile))
        rule = "symmetric in log K" if name in VARIANCE_RATES else "symmetric"
        if dof is not None:
            rule += f", Student t (nu = {dof:.1f})"
        return cls(name, value, stderr, ci, si_unit(name), wide, f"Wald, {rule}", dof)

    def contains(self, truth: float, level: str = "4sigma") -> bool:
        """Whether ``truth`` lies in the interval at ``level`` (``95`` or
        ``4sigma``): outside the 4-sigma one is "confidently wrong"."""
        low, high = self.ci95 if level == "95" else self.ci_4sigma
        return low <= truth <= high

    def to_json_dict(self) -> dict[str, Any]:
        """{"value", "stderr", "ci95", "unit", "ci_4sigma", "interval", "dof"}
        (SI; inf written as null)."""
        return {
            "value": _finite(self.value),
            "stderr": _finite(self.stderr),
            "ci95": [_finite(self.ci95[0]), _finite(self.ci95[1])],
            "unit": self.unit,
            "ci_4sigma": [_finite(self.ci_4sigma[0]), _finite(self.ci_4sigma[1])],
            "interval": self.interval,
            "dof": None if self.dof is None else _finite(self.dof),
        }


def four_sigma_quantile(dof: float) -> float:
    """The t(dof) quantile of the 4-sigma-equivalent two-sided level."""
    return distributions.t_ppf(_FOUR_SIGMA_UPPER, max(dof, 1.0))


def _wald(name: str, value: float, stderr: float, q: float) -> tuple[float, float]:
    if name in VARIANCE_RATES:
        if value > 0 and math.isfinite(stderr):
            spread = math.exp(min(q * stderr / value, 700.0))
            return (value / spread, value * spread)
        return (0.0, value + q * stderr)
    return (value - q * stderr, value + q * stderr)


@dataclass(frozen=True)
class Outlier:
    """A trial the model does not explain.

    Attributes:
        index: position of the trial in the input (0-based).
        line: its line in the trial file, or None.
        trial: its trial number, or None.
        design: its design's label (e.g. ``k=20 l=0.5 m turn``).
        mahalanobis2: squared Mahalanobis distance of its pose change from the
            model mean (model plus measurement covariance), chi^2(3) if it fits.
        p_value: chi^2(3) tail probability of that distance.
    """

    index: int
    line: int | None
    mahalanobis2: float
    p_value: float
    trial: int | None = None
    design: str = ""

    @property
    def number(self) -> int:
        """The trial number (the 1-based input position when none was given)."""
        return self.trial if self.trial is not None else self.index + 1

    def label(self) -> str:
        """``trial 17 (k=20 l=0.5 m turn)``."""
        return f"trial {self.number}" + (f" ({self.design})" if self.design else "")


@dataclass(frozen=True)
class ModelCheck:
    """Do the trials look like draws from the fitted model?

    Attributes:
        fits: no outlier and the overall test does not reject.
        verdict: plain-language summary.
        chi2: sum of the trials' squared Mahalanobis distances.
        dof: 3 n - 4 (at least 1).
        p_value: chi^2(dof) tail probability of ``chi2``.
        outliers: trials whose distance exceeds the 1 % level after a
            Bonferroni correction for n trials.
        mahalanobis2: every trial's squared distance, in input order.
    """

    fits: bool
    verdict: str
    chi2: float
    dof: int
    p_value: float
    outliers: tuple[Outlier, ...]
    mahalanobis2: tuple[float, ...]

    def to_json_dict(self) -> dict[str, Any]:
        """JSON form (per-trial distances omitted; outliers listed)."""
        return {
            "fits": self.fits,
            "verdict": self.verdict,
            "chi2": _finite(self.chi2),
            "dof": self.dof,
            "p_value": _finite(self.p_value),
            "outliers": [
                {
                    "trial": o.number,
                    "design": o.design,
                    "index": o.index,
                    "mahalanobis2": _finite(o.mahalanobis2),
                    "p_value": o.p_value,
                }
                for o in self.outliers
            ],
        }


@dataclass(frozen=True)
class Suggestion:
    """More trials of one design that would make a flagged parameter precise enough.

    Attributes:
        parameter: the parameter (E_R, E_T, K_theta or K_rho).
        design_label: the design (e.g. ``k=20 l=0.5 m turn``).
        k: the design's k.
        l_m: its leg length, metres.
        variant: its variant.
        more_trials: how many more trials (None: this design alone cannot get
            there within the search limit).
    """

    parameter: str
    design_label: str
    k: float
    l_m: float
    variant: str
    more_trials: int | None


@dataclass(frozen=True)
class Sufficiency:
    """Are there enough trials to trust every parameter?

    Attributes:
        sufficient: every parameter meets its precision target.
        verdict: plain-language summary.
        unidentified: the parameters that do not, by name.
        reasons: one sentence per such parameter.
        suggestions: per flagged parameter and design in the data, the extra
            trials needed.
    """

    sufficient: bool
    verdict: str
    unidentified: tuple[str, ...]
    reasons: tuple[str, ...]
    suggestions: tuple[Suggestion, ...]

    def to_json_dict(self) -> dict[str, Any]:
        """JSON form."""
        return {
            "sufficient": self.sufficient,
            "verdict": self.verdict,
            "unidentified": list(self.unidentified),
            "reasons": list(self.reasons),
            "suggestions": [
                {
                    "parameter": s.parameter,
                    "design": s.design_label,
                    "k": s.k,
                    "l_m": s.l_m,
                    "variant": s.variant,
                    "more_trials": s.more_trials,
                }
                for s in self.suggestions
            ],
        }


@dataclass(frozen=True)
class TrialDiagnostic:
    """How one trial sits in the fit.

    Attributes:
        trial: its trial number.
        design: its design's label.
        clean_probability: the robust fit's probability that it is not an
            outlier (1 for the Gaussian methods).
        influence: per parameter (E_R, E_T, K_theta, K_rho, then the turn
            errors where fitted), how far leaving it out moves the estimate,
            in standard errors.
        names: the parameters of ``influence``, in order.
    """

    trial: int
    design: str
    clean_probability: float
    influence: tuple[float, ...]
    names: tuple[str, ...] = PARAMETER_NAMES

    def to_json_dict(self) -> dict[str, Any]:
        """{"trial", "design", "clean_probability", "influence": {name: SE}}."""
        return {
            "trial": self.trial,
            "design": self.design,
            "clean_probability": round(self.clean_probability, 6),
            "influence": {n: round(v, 4) for n, v in zip(self.names, self.influence, strict=True)},
        }


@dataclass(frozen=True)
class EstimateResult:
    """An estimate of the four parameters with its checks.

    Attributes:
        method: ``paper`` or ``joint``.
        n_trials: number of trials used.
        params: the point estimate (SI).
        parameters: per parameter value, stderr, interval (order E_R, E_T,
            K_theta, K_rho, then a general-path fit's turn errors: ``e_turn``
            or ``e_turn_spin``/``e_turn_arc``/..., and ``K_spin``;
            odohil/science/estimators/paths.py).
        covariance: (p x p) covariance of the estimate, SI, in that order.
        correlation: (p x p) correlation matrix (nan where a stderr is inf).
        model_check: see :class:`ModelCheck`.
        sufficiency: see :class:`Sufficiency`.
        notes: how the estimate was made (designs used, convergence).
        verdict: trusted, doubtful or failed, with reasons.
        converged: whether the fit converged (always True for ``paper``).
        gaussian: the Gaussian joint maximum-likelihood estimate, reported
            beside the robust one (empty for the other methods).
        trials: per trial, its weight and influence (robust method).
        excluded: trial numbers left out on request.
        misfit: the group-bias, spread and trial-order checks
            (odohil/science/estimators/misfit.py), or None when not run.
    """

    method: str
    n_trials: int
    params: ErrorParameters
    parameters: tuple[ParameterEstimate, ...]
    covariance: tuple[tuple[float, ...], ...]
    correlation: tuple[tuple[float, ...], ...]
    model_check: ModelCheck
    sufficiency: Sufficiency
    notes: tuple[str, ...] = ()
    verdict: Verdict = TRUSTED
    converged: bool = True
    gaussian: tuple[ParameterEstimate, ...] = ()
    trials: tuple[TrialDiagnostic, ...] = ()
    excluded: tuple[int, ...] = ()
    misfit: MisfitCheck | None = None

    def parameter(self, name: str) -> ParameterEstimate:
        """The estimate of one parameter by name (KeyError when it was not
        estimated, e.g. ``e_turn`` of a four-parameter fit)."""
        for estimate in self.parameters:
            if estimate.name == name:
                return estimate
        raise KeyError(f"no parameter {name!r} in this estimate")

    @property
    def names(self) -> tuple[str, ...]:
        """The estimated parameters' names, in order (the four first)."""
        return tuple(p.name for p in self.parameters)

    def to_json_dict(self) -> dict[str, Any]:
        """{"verdict", "method", "n_trials", "parameters", "correlation",
        "model_check", "sufficiency", "notes", "excluded", "misfit" (when run),
        and for the robust method "gaussian_ml" and "trials"}, SI; non-finite
        numbers as null."""
        out: dict[str, Any] = {
            "verdict": self.verdict.to_json_dict(),
            "method": self.method,
            "n_trials": self.n_trials,
            "parameters": {p.name: p.to_json_dict() for p in self.parameters},
            "correlation": [[_finite(v) for v in row] for row in self.correlation],
            "model_check": self.model_check.to_json_dict(),
            "sufficiency": self.sufficiency.to_json_dict(),
            "notes": list(self.notes),
            "excluded": list(self.excluded),
        }
        if self.misfit is not None:
            out["misfit"] = self.misfit.to_json_dict()
        if self.gaussian:
            out["gaussian_ml"] = {p.name: p.to_json_dict() for p in self.gaussian}
        if self.trials:
            out["trials"] = [t.to_json_dict() for t in self.trials]
        return out


def _finite(value: float) -> float | None:
    return float(value) if math.isfinite(value) else None
