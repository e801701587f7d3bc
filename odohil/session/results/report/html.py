"""The report page: one self-contained ``index.html``.

The plots are inline SVG elements and the style sheet is inline; the page
refers to no other file (no ``src``, no links to files, no external style,
script or font); in-page ``#`` anchors only. The verdict comes first.
"""

from __future__ import annotations

import html
import math
from collections.abc import Mapping, Sequence

from odohil import units
from odohil.science.estimators import EstimateResult
from odohil.session.results.report.data import SessionReport, TrialPoint
from odohil.session.results.report.exports import ExportFile
from odohil.session.results.report.plots import Plot
from odohil.units import parameter_to_paper as to_paper

_CSS = """
body { font-family: sans-serif; margin: 1.5em auto; max-width: 1100px; color: #222;
       padding: 0 1em; }
table { border-collapse: collapse; margin: 1em 0; }
th, td { border: 1px solid #bbb; padding: 0.3em 0.7em; text-align: right; }
th { background: #f0f0f0; }
td.l, th.l { text-align: left; }
.plots { display: flex; flex-wrap: wrap; gap: 0.8em; }
figure { margin: 0; border: 1px solid #ddd; padding: 0.3em; }
figure svg { display: block; max-width: 100%; height: auto; }
figcaption { font-size: 0.85em; color: #555; max-width: 40em; }
.verdict { font-size: 1.2em; padding: 0.6em 0.8em; border: 2px solid; }
.verdict.good { border-color: #070; background: #f3fbf3; }
.verdict.bad { border-color: #b00; background: #fdf3f3; }
.bad { color: #b00; } .good { color: #070; }
nav a { margin-right: 1em; }
"""


def render_html(report: SessionReport, plots: Sequence[Plot], exports: Sequence[ExportFile]) -> str:
    """The page: verdict, session, estimates, trials pointed out, observables,
    the plots inline, and the list of exported files."""
    e = html.escape
    by_key = {p.key: p for p in plots}
    parts = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        '<meta name="viewport" content="width=device-width, initial-scale=1">',
        f"<title>odohil report: {e(report.folder.name)}</title>",
        f"<style>{_CSS}</style></head><body>",
        f"<h1>Odometry calibration report: {e(report.folder.name)}</h1>",
        _verdict(report),
        _session(report),
        _contents(plots),
        '<h2 id="estimates">Estimates</h2>',
    ]
    result = report.result
    if result is None:
        parts.append('<p class="bad">No estimate yet (see above).</p>')
    else:
        parts.append(_estimates_table(result))
        parts.append(f"<p>Method: {e(result.method)}. {e(' '.join(result.notes))}</p>")
        suff = result.sufficiency
        parts.append(
            f'<p class="{"good" if suff.sufficient else "bad"}">Sufficiency: {e(suff.verdict)}</p>'
        )
        if suff.suggestions:
            parts.append("<ul>")
            for s in suff.suggestions:
                more = (
                    "not reachable"
                    if s.more_trials is None
                    else units.plural(s.more_trials, "more trial")
                )
                parts.append(f"<li>{e(s.parameter)}: {e(s.design_label)}, {e(more)}</li>")
            parts.append("</ul>")
    parts.append('<h2 id="trials">Trials pointed out</h2>')
    parts.append(_marked_table(report.marked_trials))
    parts.append('<h2 id="observables">Observables per design</h2>')
    parts.append(_phi_table(report))
    ends = [p for p in plots if p.key.startswith("end-points-")]
    if ends:
        parts.append('<h2 id="end-points">End points</h2><div class="plots">')
        parts.extend(_figure(p, "") for p in ends)
        parts.append("</div>")
        parts.append(
            "<p>Dots: solved end points of the trials in the start frame. Ellipse: the "
            "model's 95 % region at the estimate (pose spread plus measurement error). "
            "Trials pointed out are labelled with their number.</p>"
        )
    if "phi1" in by_key:
        parts.append("<h2>Heading drift (the paper's Fig. 2)</h2>")
        parts.append(
            _figures(
                by_key["phi1"],
                "Each design's mean heading change phi1 with its standard error, against "
                "the signed distance driven per trial; the line's slope is E_R.",
            )
        )
    if "convergence" in by_key:
        parts.append("<h2>Convergence</h2>")
        parts.append(
            _figures(
                by_key["convergence"],
                "The Gaussian estimate (paper units) after each trial the estimate uses, with "
                "its 95 % interval (cut at the plot's edge where it is very wide); the dashed "
                "line is the final estimate, whose robust fit down-weights outliers.",
            )
        )
    if result is not None:
        mc = result.model_check
        parts.append("<h2>Model check</h2>")
        parts.append(
            f'<p class="{"good" if mc.fits else "bad"}">{e(mc.verdict)} (chi^2 = {mc.chi2:.3g}, '
            f"dof {mc.dof}, p = {mc.p_value:.3g}).</p>"
        )
        if "model-check" in by_key:
            parts.append(
                _figures(
                    by_key["model-check"],
                    "A trial above the outlier level does not fit the model at the estimate; "
                    "trials the estimate leaves out are drawn at 0.",
                )
            )
    if report.validations:
        parts.append(_validations(report, by_key))
    parts.append('<h2 id="exports">Exported files</h2>')
    parts.append("<p>Written beside this page, in the same folder:</p><ul>")
    parts.extend(f"<li><code>{e(x.name)}</code>: {e(x.description)}</li>" for x in exports)
    parts.append("</ul>")
    parts.append("</body></html>\n")
    return "\n".join(parts)


def _validations(report: SessionReport, by_key: Mapping[str, Plot]) -> str:
    """Each validation session: its verdict, the NEES tests and its plots."""
    e = html.escape
    parts = ['<h2 id="validation">Validation on paths not used for the fit</h2>']
    for i, v in enumerate(report.validations, start=1):
        where = e(str(v.folder.relative_to(report.folder)))
        if v.result is None:
            parts.append(f'<p class="bad">{e(v.path)} ({where}): {e(v.problem)}</p>')
            continue
        r = v.result
        status = "PASS" if r.passed else "FAIL"
        parts.append(
            f'<p class="{"good" if r.passed else "bad"}">{e(v.path)} ({where}): {status}, '
            f"{units.plural(r.n_trials, 'trial')}, each test at level {r.level:g}"
            f"{': ' + e('; '.join(r.reasons())) if r.reasons() else ''}.</p>"
        )
        parts.append(f"<p>{e(v.sensitivity)}.</p>")
        parts.append(
            "<table><tr><th>test</th><th>statistic</th><th>dof</th><th>p-value</th>"
            "<th>threshold</th><th>result</th></tr>"
        )
        for t in r.tests:
            parts.append(
                f"<tr><td>{e(t.name)}</td><td>{t.statistic:.4g}</td><td>{t.dof}</td>"
                f"<td>{t.p_value:.3g}</td><td>{t.threshold:.4g}</td>"
                f"<td>{'pass' if t.passed else 'FAIL'}</td></tr>"
            )
        parts.append("</table>")
        keys = sorted(k for k in by_key if k.startswith(f"validation-{i}-"))
        parts.extend(
            _figures(
                by_key[k],
                "Dots: the validation trials' end points; ellipse: the calibrated model's "
                "95 % region for the path (pose spread, measurement error and the "
                "estimate's own uncertainty).",
            )
            for k in keys
        )
    return "\n".join(parts)


def _verdict(report: SessionReport) -> str:
    e = html.escape
    result = report.result
    if result is None:
        return f'<p class="verdict bad">No estimate yet: {e(report.problem)}</p>'
    verdict = result.verdict
    reasons = "; ".join(verdict.reasons)
    warning = (
        ""
        if verdict.trusted
        else "<br>This estimate is not trusted; these files were written on request "
        "(--force). Do not feed its numbers to a filter before the reasons are settled."
    )
    return (
        f'<p class="verdict {"good" if verdict.trusted else "bad"}">Verdict: '
        f"<strong>{e(verdict.status)}</strong>{e(': ' + reasons if reasons else '')}"
        f"{warning}</p>"
    )


def _session(report: SessionReport) -> str:
    e = html.escape
    state = report.state
    plan = state.plan.to_text() if state.plan else "none"
    return (
        f"<p>Plan <code>{e(plan)}</code>; {len(state.completed)} of "
        f"{units.plural(state.plan.n_trials if state.plan else 0, 'trial')} completed"
        f"{' (session finished)' if state.finished else ' (session not finished)'}; "
        f"{state.voided} attempt(s) voided. Robot description: "
        f"<code>{e(state.header.robot_path or 'journaled')}</code>.</p>"
    )


def _contents(plots: Sequence[Plot]) -> str:
    links = [("estimates", "Estimates"), ("trials", "Trials pointed out")]
    links += [("observables", "Observables")]
    links += [(p.key, p.title) for p in plots]
    links += [("exports", "Exported files")]
    return "<nav>" + "".join(f'<a href="#{k}">{html.escape(t)}</a>' for k, t in links) + "</nav>"


def _figure(plot: Plot, caption: str) -> str:
    text = f"<figcaption>{html.escape(caption)}</figcaption>" if caption else ""
    return f'<figure id="{html.escape(plot.key)}">{plot.svg}{text}</figure>'


def _figures(plot: Plot, caption: str) -> str:
    return f'<div class="plots">{_figure(plot, caption)}</div>'


def _marked_table(trials: Sequence[TrialPoint]) -> str:
    if not trials:
        return (
            "<p>None: every trial is used, none is flagged, and the robust fit "
            "down-weights none.</p>"
        )
    rows = [
        "<table><tr><th>trial</th><th class=l>design</th><th class=l>what</th>"
        "<th class=l>why</th></tr>"
    ]
    for t in trials:
        what, why = [], []
        if t.excluded:
            what.append("excluded")
            why.append("left out on request (--exclude)")
        if t.ambiguous:
            what.append("ambiguous, left out")
            why.append("two candidate poses stay plausible")
        if t.flagged:
            what.append("flagged")
            why.append(t.note or "the pose from the marks is in doubt")
        if t.down_weighted and t.clean_probability is not None:
            what.append("outlier, down-weighted")
            why.append(
                f"the robust fit gives it a {t.clean_probability:.2g} probability of being clean"
            )
        rows.append(
            f"<tr><td>{t.trial}</td><td class=l>{html.escape(t.design)}</td>"
            f"<td class=l>{html.escape(', '.join(what))}</td>"
            f"<td class=l>{html.escape('; '.join(why))}</td></tr>"
        )
    rows.append("</table>")
    return "\n".join(rows)


def _estimates_table(result: EstimateResult) -> str:
    rows = [
        "<table><tr><th class=l>parameter</th><th>estimate</th><th>standard error</th>"
        "<th>95 % interval</th><th class=l>unit</th></tr>"
    ]
    for p in result.parameters:
        lo, hi = (to_paper(p.name, v) for v in p.ci95)
        rows.append(
            f"<tr><td class=l>{p.name}</td><td>{to_paper(p.name, p.value):.4g}</td>"
            f"<td>{_fmt(to_paper(p.name, p.stderr))}</td><td>[{_fmt(lo)}, {_fmt(hi)}]</td>"
            f"<td class=l>{units.unit_column(p.name, 'paper')}</td></tr>"
        )
    rows.append("</table>")
    return "\n".join(rows)


def _phi_table(report: SessionReport) -> str:
    rows = [
        "<table><tr><th class=l>design</th><th>trials used</th><th>phi1 (deg)</th>"
        "<th>phi2 (deg^2)</th><th>phi3 (mm)</th><th>phi4 (mm)</th><th>phi5 (mm^2)</th></tr>"
    ]
    for d in report.designs:
        label = html.escape(d.design.label())
        if d.phi is None:
            rows.append(
                f"<tr><td class=l>{label}</td><td>{d.n_used}</td>"
                "<td colspan=5 class=l>needs 2 trials</td></tr>"
            )
            continue
        phi = d.phi
        rows.append(
            f"<tr><td class=l>{label}</td><td>{phi.n_trials}</td>"
            f"<td>{units.radians_to_degrees(phi.phi1):.4g}</td>"
            f"<td>{units.rad2_to_deg2(phi.phi2):.4g}</td><td>{1e3 * phi.phi3:.4g}</td>"
            f"<td>{1e3 * phi.phi4:.4g}</td><td>{1e6 * phi.phi5:.4g}</td></tr>"
        )
    rows.append("</table>")
    return "\n".join(rows)


def _fmt(value: float) -> str:
    return f"{value:.3g}" if math.isfinite(value) else "undetermined"
