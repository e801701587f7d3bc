"""What ``odohil report`` writes: a session folder's own report (designs,
convergence) unless a path family or direction is chosen, else the summary
page of the outcome ``odohil estimate`` would print; with the exports of
odohil/session/results/exports.py beside it."""

from __future__ import annotations

from collections.abc import Collection, Sequence
from pathlib import Path

from odohil.session.results.exports import export_files
from odohil.session.results.outcome import EstimateOutcome, Selection, source_kind
from odohil.session.results.report import SessionReport, load_report, write_report
from odohil.session.results.report.path_page import write_path_report
from odohil.session.trials.logs import ImportOptions

__all__ = [
    "session_report",
    "write_any_report",
]


def session_report(
    sources: Sequence[Path],
    exclude: Collection[int],
    recording: ImportOptions,
    selection: Selection,
) -> SessionReport | None:
    """The report of the session folder ``sources`` names (``exclude`` left
    out of its estimate); None when they name a trial file or a recording, or
    ``selection`` chooses a path family or direction (the summary page then).

    Raises:
        JournalError, MeasurementError, TrialFileError: as :func:`load_report`
            and :func:`~odohil.session.results.outcome.source_kind`.
    """
    if source_kind(sources, recording) != "session" or selection.chosen:
        return None
    return load_report(sources[0], exclude)


def write_any_report(report: SessionReport | EstimateOutcome, out: Path, source: str) -> list[Path]:
    """Write ``report`` (a session's, else an outcome's summary page) and, when
    there is an estimate, the exports named after ``source`` into ``out``;
    the files written, ``index.html`` last.

    Raises:
        OSError: the folder cannot be written.
    """
    outcome = report if isinstance(report, EstimateOutcome) else report.outcome
    assert outcome is not None  # load_report always sets it
    result = outcome.result
    extra = () if result is None else export_files(result, source=source)
    if isinstance(report, SessionReport):
        return write_report(report, out, extra)
    return write_path_report(outcome, out, extra)
