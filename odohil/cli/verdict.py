"""Plain-text lines for an estimate's verdict and the Gaussian fit beside the robust one."""

from __future__ import annotations

from odohil import units
from odohil.science.estimators import EstimateResult
from odohil.science.estimators.verdict import Verdict


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
    for name in ("E_R", "E_T", "K_theta", "K_rho"):
        if name not in by_name:
            continue
        value = by_name[name].value
        if name == "E_R":
            value = units.rad_per_m_to_deg_per_m(value)
        elif name == "K_theta":
            value = units.rad2_per_m_to_deg2_per_m(value)
        parts.append(f"{name} {value:.4g}")
    return "Gaussian joint ML beside (paper units): " + ", ".join(parts)
