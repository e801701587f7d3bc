"""Plain-text lines for an estimate's verdict and the Gaussian fit beside the robust one."""

from __future__ import annotations

from odohil import units
from odohil.science.estimators import EstimateResult
from odohil.science.estimators.verdict import Verdict
from odohil.science.parameters import PARAMETER_NAMES


def verdict_line(verdict: Verdict) -> str:
    """``verdict: TRUSTED`` or ``verdict: DOUBTFUL (reason; reason)``."""
    text = f"verdict: {verdict.status.upper()}"
    if verdict.reasons:
        text += " (" + "; ".join(verdict.reasons) + ")"
    return text


def gaussian_line(
    result: EstimateResult, system: units.UnitSystem = units.DEFAULT_UNIT_SYSTEM
) -> str:
    """The Gaussian joint maximum-likelihood values beside the robust ones, in
    ``system``'s units."""
    by_name = {p.name: p for p in result.gaussian}
    parts = []
    for name in PARAMETER_NAMES:
        if name not in by_name:
            continue
        value = f"{units.parameter_in(name, by_name[name].value, system):.4g}"
        parts.append(f"{name} {units.with_unit(value, units.parameter_unit(name, system))}")
    return "Gaussian joint ML beside: " + ", ".join(parts)
