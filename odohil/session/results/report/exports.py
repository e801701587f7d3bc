"""The files the report writes beside ``index.html``: the estimate for other tools.

Each export is an :class:`ExportFile`; :func:`standard_exports` gives the
report's own (``parameters.json``). The filter formats (odohil/session/results/exports.py,
the files ``odohil export`` writes) join by passing their files to
:func:`odohil.session.results.report.write_report`; ``index.html`` lists every export
by name with its description.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from typing import Any

from odohil.session.results.report.data import SessionReport


@dataclass(frozen=True)
class ExportFile:
    """One file written beside ``index.html``.

    Attributes:
        name: its file name in the report folder (no folder part).
        text: its content (UTF-8 text).
        description: what it is, for the report's list of exports.
    """

    name: str
    text: str
    description: str


def standard_exports(report: SessionReport) -> tuple[ExportFile, ...]:
    """``parameters.json``: the estimate as ``odohil estimate --json`` prints it."""
    return (
        ExportFile(
            "parameters.json",
            json.dumps(parameters_json(report), indent=2) + "\n",
            "the estimate (SI units), as odohil estimate --json prints it",
        ),
    )


def parameters_json(report: SessionReport) -> dict[str, Any]:
    """The estimate's JSON object (SI), as ``odohil estimate --json`` prints it
    (odohil/session/results/outcome.py); without an estimate its verdict is ``no
    estimate``, with ``error`` saying why."""
    if report.outcome is not None:
        data = report.outcome.to_json_dict()
    elif report.result is not None:
        data = report.result.to_json_dict()
    else:
        data = {"n_trials": len(report.state.completed)}
    if report.result is None:
        data["error"] = report.problem
    return data
