"""An estimate's outcome in plain words: the verdict line every command that
estimates prints, why an estimate is not exported, its notes, the Gaussian fit
beside, the trials still needed, and parameter values in a unit system. The
CLI colours and lays these out; their meaning is the session's."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from odohil import units
from odohil.science.estimators import EstimateResult, ParameterEstimate
from odohil.science.estimators.verdict import Verdict
from odohil.science.parameters import PARAMETER_NAMES
from odohil.session.results.outcome import EstimateOutcome
from odohil.session.table_text import TableText

__all__ = [
    "DETECT_HELP",
    "DETECT_SYNTAX",
    "export_refusal_lines",
    "more_trials_lines",
    "outcome_line",
    "outcome_notes",
    "parameters_line",
    "parameters_text",
    "refusal_line",
    "sizing_lines",
    "test_words",
    "verdict_line",
]

DETECT_SYNTAX = (
    "NAME=VALUE[,NAME=VALUE...], the error to catch in the paper's units: E_R deg/m, E_T "
    "(0.02 or 2%), K_theta deg^2/m, K_rho m (e.g. E_R=0.4,K_theta=0.1)"
)
DETECT_HELP = (
    f"The calibration error a validation must catch with probability 0.9: {DETECT_SYNTAX}. "
    "It chooses the trials to drive (with --trials, checks them), printed before anything "
    "moves; exit 2 when the path cannot."
)
"""``--detect`` of validate and the wizard (odohil/session/commands/validate_power.py)."""


def test_words(test: str) -> str:
    """``the bias theta test``, ``the overall NEES test``."""
    return f"the {test} test" if test.startswith("bias") else f"the {test} NEES test"


def sizing_lines(settings: Mapping[str, Any]) -> list[str]:
    """The trial count ``--detect`` chose (a validation session's ``settings``
    hold it as ``sizing``: odohil/session/commands/validate_power.py
    ``Sizing.to_json_dict``): ``trials: 6 of forth-back:2,1.5 (planned by
    --detect)``, then per error its power; none without it."""
    sizing = settings.get("sizing")
    if not sizing:
        return []
    how = "given by --trials" if sizing["given"] else "planned by --detect"
    out = [f"trials: {sizing['trials']} of {sizing['path']} ({how})"]
    for name, c in sizing["detect"].items():
        fewest = units.plural(int(c["trials"] or 0), "trial")
        out.append(
            f"  {name} off by {units.paper_text(name, float(c['error']))}: caught with "
            f"probability {c['power']:.3f} ({test_words(c['test'])}; {sizing['power']:g} from "
            f"{fewest} on)"
        )
    return out


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


def refusal_line(outcome: EstimateOutcome, force: str | None, undone: str) -> str:
    """Why an estimate is not used and how to go on (``force``: what --force
    does, e.g. "export it", None when it does not help; ``undone``: "nothing
    written"), after ``refused:``."""
    what = "the estimate is not " + ("precise enough" if outcome.trusted else "trusted")
    if outcome.result is None:
        what = "there is no estimate"
    return (
        f"{what}; {undone}. Fix the trials (or leave them out with --exclude N,...), add trials"
        + (f", or pass --force to {force} with the verdict stated." if force else ".")
    )


def number_text(name: str, value_si: float, system: units.UnitSystem, digits: int = 4) -> str:
    """A parameter's value (SI) as text in ``system``'s units, without the unit;
    "-" when not finite (undetermined, or an unbounded interval end)."""
    if not math.isfinite(value_si):
        return "-"
    return f"{units.parameter_in(name, value_si, system):.{digits}g}"


def parameters_line(values_si: Mapping[str, float], system: units.UnitSystem) -> str:
    """``E_R = -1 deg/m, E_T = -0.05, K_theta = 0.3 deg^2/m, K_rho = 0.0009 m``."""
    return ", ".join(
        f"{name} = "
        + units.with_unit(number_text(name, value, system), units.parameter_unit(name, system))
        for name, value in values_si.items()
    )


def inside(entry: ParameterEstimate, value: float) -> bool:
    """Whether ``value`` lies in the entry's 95 % interval (a non-finite end: unbounded)."""
    low, high = entry.ci95
    return (not math.isfinite(low) or low <= value) and (not math.isfinite(high) or value <= high)


def parameters_text(
    result: EstimateResult,
    system: units.UnitSystem = units.DEFAULT_UNIT_SYSTEM,
    title: str | None = None,
    truth: Mapping[str, float] | None = None,
) -> TableText:
    """The four parameters with standard errors and 95 % intervals in
    ``system``'s units (:func:`parameter_rows`); with ``truth`` (SI values by
    name) a truth column in the same units and whether the interval holds it.
    The title: ``title (method, N trials)``, else ``Estimate after N trials``."""
    columns = ["parameter", "estimate", "std. error", "95 % interval", "unit"]
    if truth is not None:
        columns += ["truth", "truth inside"]
    trials = units.plural(result.n_trials, "trial")
    title = f"{title} ({result.method}, {trials})" if title else f"Estimate after {trials}"
    rows = parameter_rows(result, system, truth)
    return TableText(title, columns, rows, ("parameter", "unit"), flagged=("NO",), title_left=True)


def parameter_rows(
    result: EstimateResult,
    system: units.UnitSystem,
    truth: Mapping[str, float] | None = None,
) -> list[list[str]]:
    """Each parameter's row of the parameters table: name, estimate, standard
    error, 95 % interval and unit in ``system``'s units; with ``truth`` (SI
    values by name) also the truth in the same units and whether the interval
    holds it (``yes``, else ``NO``)."""
    rows = []
    for p in result.parameters:
        low, high = p.ci95
        row = [
            p.name,
            number_text(p.name, p.value, system),
            number_text(p.name, p.stderr, system, digits=2),
            f"[{number_text(p.name, low, system)}, {number_text(p.name, high, system)}]",
            units.unit_column(p.name, system),
        ]
        if truth is not None:
            row.append(number_text(p.name, truth[p.name], system))
            row.append("yes" if inside(p, truth[p.name]) else "NO")
        rows.append(row)
    return rows


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


def outcome_notes(outcome: EstimateOutcome, system: units.UnitSystem) -> list[str]:
    """What is printed below an estimate's table: the sufficiency check's
    reasons, notes, refusals, the Gaussian fit beside, and the trials left out
    (on request, ambiguous) or flagged; how the windows of ``--window-m`` went.
    Without an estimate only the windows."""
    result = outcome.result
    windows = [] if outcome.windows is None else outcome.windows.lines()
    if result is None:
        return windows
    lines = windows + [f"  - {reason}" for reason in result.sufficiency.reasons]
    lines += [f"note: {note}" for note in result.notes] + export_refusal_lines(outcome)
    if result.gaussian:
        lines.append(gaussian_line(result, system))
    if result.excluded:
        lines.append(
            f"left out (--exclude): {units.plural_noun(len(result.excluded), 'trial')} "
            + ", ".join(map(str, result.excluded))
        )
    if outcome.ambiguous:
        lines.append(
            "ambiguous trials left out (two candidate poses stay plausible): "
            + ", ".join(map(str, outcome.ambiguous))
        )
    if outcome.flagged:
        named = ", ".join(f"{trial} ({note})" for trial, note in outcome.flagged)
        lines.append(f"flagged trials (pose from the marks in doubt): {named}")
    return lines


def more_trials_lines(result: EstimateResult, remaining_in_plan: int) -> list[str]:
    """How many more trials reach the target precision (the sufficiency
    check): per design the largest number any parameter needs."""
    suff = result.sufficiency
    if suff.sufficient:
        return ["Target precision reached for every parameter."]
    lines = [suff.verdict or "precision target not reached"]
    needed: dict[str, int | None] = {}
    for s in suff.suggestions:
        design, more = s.design_label, s.more_trials
        if design not in needed or (
            (known := needed[design]) is not None and (more is None or more > known)
        ):
            needed[design] = more
    for design, more in needed.items():
        reach = "reaches" if more == 1 else "reach"
        more_text = (
            f"{units.plural(more, 'more trial')} {reach} the target" if more is not None else ""
        )
        lines.append(f"  {design}: " + ("cannot reach it alone" if more is None else more_text))
    remain = "remains" if remaining_in_plan == 1 else "remain"
    lines.append(f"  ({units.plural(remaining_in_plan, 'trial')} {remain} in the plan)")
    return lines


def live_e_r(result: EstimateResult, system: units.UnitSystem) -> str | None:
    """``E_R -0.2021 deg/m``: the live E_R beside a progress bar; None while not finite."""
    e_r = result.parameter("E_R").value
    if not math.isfinite(e_r):
        return None
    value = units.parameter_in("E_R", e_r, system)
    return f"E_R {value:+.4g} {units.parameter_unit('E_R', system)}"
