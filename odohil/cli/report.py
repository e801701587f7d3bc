"""``odohil report``: a self-contained HTML report of a session (or of a
trial file or a recording, through the one loader), with exports."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console

from odohil.cli.estimate import SOURCES_HELP, load_outcome
from odohil.cli.options import robot_option
from odohil.cli.recording_options import source_options
from odohil.cli.render import bad_inputs, verdict_or_refuse
from odohil.session.commands.report import session_report, write_any_report
from odohil.session.results.outcome import Selection
from odohil.session.trials.logs import ImportOptions


@source_options()
def report(
    sources: Annotated[list[Path], typer.Argument(help=SOURCES_HELP)],
    out: Annotated[Path, typer.Option("--out", help="Folder to write the report into (created).")],
    force: Annotated[
        bool,
        typer.Option(
            "--force",
            help="Write the report and exports even when the estimate is not trusted "
            "(the files then state its verdict).",
        ),
    ] = False,
    robot: Annotated[
        Path | None,
        robot_option(" Needed for raw marks and recordings (a session journals its own)."),
    ] = None,
    *,
    exclude: frozenset[int],
    recording: ImportOptions,
    selection: Selection,
) -> None:
    """Write index.html (plots inline), parameters.json and the files of odohil export to --out.

    A session's page plots its designs and convergence; a trial file's or a
    recording's (read as `estimate` reads them, with --robot and import's
    options) is a summary: verdict, parameters, mean residuals per path family
    and direction. An estimate that is not trusted, none at all, or one too
    imprecise to export (a design below the planner's minimum trials, a
    correction whose 95 % interval is wider than itself) is refused (exit 3,
    nothing written) unless --force; exit 2 on a bad source or --exclude.
    """
    console = Console(stderr=True)
    with bad_inputs(console):
        data = session_report(sources, exclude, recording, selection)
    if data is not None:
        assert data.outcome is not None  # load_report always sets it
        outcome = data.outcome
    else:
        outcome = load_outcome(sources, robot, exclude, console, "robust", recording, selection)
    verdict_or_refuse(console, outcome, force, "write the report")
    with bad_inputs(console):
        files = write_any_report(outcome if data is None else data, out, sources[0].name)
    if not outcome.exportable:
        console.print("written with --force although refused without it")
    console.print(f"wrote {len(files)} files; open {out / 'index.html'}")
