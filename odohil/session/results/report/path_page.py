"""The report of an estimate from general-path trials (a general-path trial
file or a recording, odohil/session/results/outcome.py): ``index.html`` with the
verdict, the parameters, the notes and each path family and direction's mean
residuals, and ``parameters.json`` beside the exports. A session's report
(odohil/session/results/report/html.py) also plots its designs and convergence; these
trials have no designs, so the page is a summary without plots."""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from html import escape
from pathlib import Path

import numpy as np

from odohil import units
from odohil.science.estimators.paths import predict
from odohil.session.results.outcome import EstimateOutcome
from odohil.session.results.report.exports import ExportFile

__all__ = [
    "write_path_report",
]


def path_exports(outcome: EstimateOutcome) -> tuple[ExportFile, ...]:
    """``parameters.json``: the estimate as ``odohil estimate --json`` prints it."""
    data = outcome.to_json_dict()
    if outcome.result is None:
        data["error"] = outcome.problem
    return (
        ExportFile(
            "parameters.json",
            json.dumps(data, indent=2) + "\n",
            "the estimate (SI units), as odohil estimate --json prints it",
        ),
    )


def _groups(outcome: EstimateOutcome) -> list[str]:
    """One table row per family and direction: trials, distance, and the mean
    residual per axis with its standard error (mm, mm, deg)."""
    result = outcome.result
    trials = [t for t in outcome.path_trials if t.trial not in set(outcome.excluded)]
    if result is None or not trials:
        return []
    rows: dict[tuple[str, str], list[tuple[float, np.ndarray]]] = {}
    for trial, p in zip(trials, predict(trials, result), strict=True):
        rows.setdefault((trial.family, trial.direction), []).append(
            (trial.path.distance_m, p.residual)
        )
    out = []
    for (family, direction), members in rows.items():
        r = np.array([m[1] for m in members])
        n = len(members)
        se = r.std(axis=0, ddof=1) / math.sqrt(n) if n > 1 else np.full(3, math.nan)
        cells = [
            f"{1e3 * r[:, 0].mean():+.2f} ± {1e3 * se[0]:.2f} mm",
            f"{1e3 * r[:, 1].mean():+.2f} ± {1e3 * se[1]:.2f} mm",
            f"{math.degrees(r[:, 2].mean()):+.3f} ± {math.degrees(se[2]):.3f} deg",
        ]
        distance = sum(m[0] for m in members)
        out.append(
            f"<tr><td>{escape(family)}</td><td>{escape(direction)}</td><td>{n}</td>"
            f"<td>{distance:.3f}</td>" + "".join(f"<td>{c}</td>" for c in cells) + "</tr>"
        )
    return out


def render_path_page(outcome: EstimateOutcome, exports: Sequence[ExportFile]) -> str:
    """The page (self-contained HTML)."""
    e = escape
    parts = [
        "<!DOCTYPE html><html><head><meta charset='utf-8'>",
        f"<title>odohil report: {e(outcome.source)}</title></head><body>",
        f"<h1>odohil report</h1><p>General-path trials from <code>{e(outcome.source)}</code>: "
        f"{units.plural(len(outcome.path_trials), 'trial')}.</p>",
        f"<h2>Verdict: {e(outcome.status)}</h2>",
    ]
    if outcome.windows is not None:  # how a continuous log's windows went (--window-m)
        named = outcome.windows.named()
        parts.append(f"<p>{e(outcome.windows.summary())}</p>")
        parts += ["<ul>", *[f"<li>{e(n)}</li>" for n in named], "</ul>"] if named else []
    result = outcome.result
    reasons = [outcome.problem] if result is None else list(result.verdict.reasons)
    parts += ["<ul>", *[f"<li>{e(r)}</li>" for r in reasons], "</ul>"] if reasons else []
    if outcome.export_refusals:
        parts.append("<p>Not precise enough to export:</p><ul>")
        parts += [f"<li>{e(r)}</li>" for r in outcome.export_refusals]
        parts.append("</ul>")
    if result is not None:
        parts.append(
            "<h2>Parameters</h2><table border='1'><tr><th>parameter</th><th>estimate</th>"
            "<th>std. error</th><th>95 % interval</th><th>unit</th></tr>"
        )
        for p in result.parameters:
            v, se = (units.parameter_to_paper(p.name, x) for x in (p.value, p.stderr))
            low, high = (units.parameter_to_paper(p.name, x) for x in p.ci95)
            parts.append(
                f"<tr><td>{e(p.name)}</td><td>{v:.4g}</td><td>{se:.2g}</td>"
                f"<td>[{low:.4g}, {high:.4g}]</td>"
                f"<td>{e(units.parameter_unit(p.name, 'paper'))}</td></tr>"
            )
        parts.append("</table>")
        parts.append(f"<p>Model check: {e(result.model_check.verdict)}</p>")
        parts += ["<ul>", *[f"<li>{e(n)}</li>" for n in result.notes], "</ul>"]
        rows = _groups(outcome)
        if rows:
            parts.append(
                "<h2>Mean residuals by path family and direction</h2>"
                "<p>Measured minus predicted at the fitted parameters, ± the standard "
                "error of the mean from the trials' own scatter.</p>"
                "<table border='1'><tr><th>family</th><th>direction</th><th>trials</th>"
                "<th>distance (m)</th><th>x</th><th>y</th><th>heading</th></tr>"
            )
            parts += rows
            parts.append("</table>")
    parts.append("<h2>Files</h2><ul>")
    parts += [f"<li><code>{e(x.name)}</code>: {e(x.description)}</li>" for x in exports]
    parts.append("</ul></body></html>")
    return "\n".join(parts) + "\n"


def write_path_report(
    outcome: EstimateOutcome, out_dir: str | Path, extra_exports: Sequence[ExportFile] = ()
) -> list[Path]:
    """Write ``index.html``, ``parameters.json`` and ``extra_exports`` into
    ``out_dir`` (created); returns the files written, ``index.html`` last.

    Raises:
        OSError: the folder cannot be written.
    """
    exports = (*path_exports(outcome), *extra_exports)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    written = []
    for export in exports:
        path = out / export.name
        path.write_text(export.text, encoding="utf-8")
        written.append(path)
    index = out / "index.html"
    index.write_text(render_path_page(outcome, exports), encoding="utf-8")
    written.append(index)
    return written
