"""Plain-text lines for an estimate's verdict and the Gaussian fit beside the robust one."""

from __future__ import annotations

from odohil import units
from odohil.science.estimators import EstimateResult
from odohil.science.estimators.verdict import Verdict
from odohil.science.parameters import PARAMETER_NAMES
from odohil.session.outcome import EstimateOutcome


def verdict_line(verdict: Verdict) -> str:
    """``verdict: TRUSTED`` or ``verdict: DOUBTFUL (reason; reason)``."""
    text = f"verdict: {verdict.status.upper()}"
    if verdict.reasons:
        text += " (" + "; ".join(verdict.reasons) + ")"
    return text


def outcome_line(outcome: EstimateOutcome) -> str:
    """The verdict line of any command that estimates: :func:`verdict_line`,
    or ``verdict: NO ESTIMATE (why)``."""
    if outcome.result is None:
        return f"verdict: NO ESTIMATE ({outcome.problem})"
    return verdict_line(outcome.result.verdict)


def export_refusal_lines(outcome: EstimateOutcome) -> list[str]:
    """Why a trusted estimate is not exported without --force, one line each."""
    return [f"not precise enough to export: {reason}" for reason in outcome.export_refusals]


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
