"""``odohil report``: a self-contained HTML report of a session (or of a
trial file or a recording, through the one loader), with exports."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console
from rich.markup import escape

from odohil.cli.estimate import SOURCES_HELP, load_outcome
from odohil.cli.exclude import EXCLUDE_HELP, parse_exclude
from odohil.cli.exit_codes import EXIT_BAD_INPUT, exit_for_outcome
from odohil.cli.recording_options import (
    MAX_TIME_DIFF_DEFAULT,
    MAX_TRUTH_GAP_DEFAULT,
    MIN_EDGE_REST_DEFAULT,
    MIN_REST_DEFAULT,
    ODOM_TOPIC_DEFAULT,
    TRUTH_TOPIC_DEFAULT,
    DirectionOption,
    FamilyOption,
    LogFormatOption,
    MaxTimeDiffOption,
    MaxTruthGapOption,
    MinEdgeRestOption,
    MinRestOption,
    OdomTopicOption,
    TimeOffsetOption,
    TruthTopicOption,
    import_options,
)
from odohil.cli.robot_option import ROBOT_HELP, robot_callback
from odohil.cli.verdict import export_refusal_lines, outcome_line
from odohil.errors import OdohilError
from odohil.session.exports import export_files
from odohil.session.outcome import Selection, source_kind
from odohil.session.report import load_report, write_report
from odohil.session.report.path_page import write_path_report


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
    exclude: Annotated[str | None, typer.Option("--exclude", help=EXCLUDE_HELP)] = None,
    robot: Annotated[
        Path | None,
        typer.Option(
            "--robot",
            callback=robot_callback,
            help=ROBOT_HELP + " Needed for raw marks and recordings (a session journals its own).",
        ),
    ] = None,
    family: FamilyOption = None,
    direction: DirectionOption = None,
    log_format: LogFormatOption = None,
    odom_topic: OdomTopicOption = ODOM_TOPIC_DEFAULT,
    truth_topic: TruthTopicOption = TRUTH_TOPIC_DEFAULT,
    max_time_diff: MaxTimeDiffOption = MAX_TIME_DIFF_DEFAULT,
    time_offset: TimeOffsetOption = 0.0,
    min_rest: MinRestOption = MIN_REST_DEFAULT,
    min_edge_rest: MinEdgeRestOption = MIN_EDGE_REST_DEFAULT,
    max_truth_gap: MaxTruthGapOption = MAX_TRUTH_GAP_DEFAULT,
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
    data = None
    try:
        recording = import_options(
            log_format,
            odom_topic,
            truth_topic,
            max_time_diff,
            time_offset,
            min_rest,
            min_edge_rest,
            max_truth_gap,
        )
        selection = Selection(family, direction)
        if source_kind(sources, recording) == "session" and not selection.chosen:
            data = load_report(sources[0], parse_exclude(exclude))
            outcome = data.outcome
            assert outcome is not None  # load_report always sets it
        else:
            outcome = load_outcome(
                sources, robot, parse_exclude(exclude), console, "robust", recording, selection
            )
    except (OdohilError, OSError) as exc:
        console.print(f"[red]error:[/red] {escape(str(exc))}")
        raise typer.Exit(EXIT_BAD_INPUT) from None
    console.print(outcome_line(outcome), highlight=False)
    if not outcome.exportable and not force:
        for line in export_refusal_lines(outcome):
            console.print(line, highlight=False)
        what = (
            "there is no estimate"
            if outcome.result is None
            else "the estimate is not " + ("trusted" if not outcome.trusted else "precise enough")
        )
        console.print(
            f"[red]refused:[/red] {what}; nothing written. Fix the trials (or leave them "
            "out with --exclude N,...), add trials, or pass --force to write the report "
            "with the verdict stated in it."
        )
        raise typer.Exit(exit_for_outcome(outcome, export=True))
    try:
        result = outcome.result
        extra = () if result is None else export_files(result, source=sources[0].name)
        files = (
            write_report(data, out, extra)
            if data is not None
            else write_path_report(outcome, out, extra)
        )
    except OSError as exc:
        console.print(f"[red]error:[/red] {escape(str(exc))}")
        raise typer.Exit(EXIT_BAD_INPUT) from None
    if not outcome.exportable:
        console.print("written with --force although refused without it")
    console.print(f"wrote {len(files)} files; open {out / 'index.html'}")


def register(app: typer.Typer) -> None:
    """Add ``report`` to the ``odohil`` app."""
    app.command("report")(report)
