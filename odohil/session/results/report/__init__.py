"""The session report: what it shows (:mod:`.data`), its plots (:mod:`.plots`,
matplotlib), its page (:mod:`.html`) and the files exported beside it
(:mod:`.exports`).
Importing this package does not import matplotlib (every ``odohil`` command
would pay for it); :func:`write_report` does.

:func:`write_report` writes, into one folder: ``index.html`` (self-contained:
every plot inline, referring to no other file) and the exports
(``parameters.json`` and any further :class:`ExportFile` the caller
passes: ``odohil report`` passes the filter formats of odohil/session/results/exports.py).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from odohil.session.results.report.data import (
    ConvergencePoint,
    DesignReport,
    SessionReport,
    TrialPoint,
    load_report,
)
from odohil.session.results.report.exports import (
    ExportFile,
    parameters_json,
    standard_exports,
)

__all__ = [
    "ConvergencePoint",
    "DesignReport",
    "ExportFile",
    "SessionReport",
    "TrialPoint",
    "load_report",
    "parameters_json",
    "standard_exports",
    "write_report",
]


def write_report(
    report: SessionReport, out_dir: str | Path, extra_exports: Sequence[ExportFile] = ()
) -> list[Path]:
    """Write ``index.html`` and the exports into ``out_dir`` (created); returns
    the files written, ``index.html`` last.

    Args:
        report: what to show (see :func:`load_report`).
        out_dir: the report folder.
        extra_exports: more files to write beside the standard exports (listed
            in the page too).

    Raises:
        ValueError: an export's name is not a plain file name, or is used twice.
        OSError: the folder cannot be written.
    """
    exports = (*standard_exports(report), *extra_exports)
    names = [x.name for x in exports]
    for name in names:
        if name != Path(name).name or name in ("", ".", "..", "index.html"):
            raise ValueError(f"an export's name must be a plain file name, got {name!r}")
    if len(set(names)) != len(names):
        raise ValueError(f"two exports share a name: {names}")
    # matplotlib takes most of a second to import: only when a report is written.
    from odohil.session.results.report.html import render_html
    from odohil.session.results.report.plots import report_plots

    page = render_html(report, report_plots(report), exports)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    written = []
    for export in exports:
        path = out / export.name
        path.write_text(export.text, encoding="utf-8")
        written.append(path)
    index = out / "index.html"
    index.write_text(page, encoding="utf-8")
    written.append(index)
    return written
