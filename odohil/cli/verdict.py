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


def gaussian_line(result: EstimateResult) -> str:
    """The Gaussian joint maximum-likelihood values beside the robust ones, paper units."""
    by_name = {p.name: p for p in result.gaussian}
    parts = []
    for name in PARAMETER_NAMES:
        if name not in by_name:
            continue
        parts.append(f"{name} {units.parameter_to_paper(name, by_name[name].value):.4g}")
    return "Gaussian joint ML beside (paper units): " + ", ".join(parts)
