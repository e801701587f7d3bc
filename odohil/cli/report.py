"""``odohil report``: a self-contained HTML report of a session, with exports."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console

from odohil.cli.exclude import EXCLUDE_HELP, parse_exclude
from odohil.cli.exit_codes import EXIT_BAD_INPUT, exit_for_outcome
from odohil.cli.verdict import export_refusal_lines, outcome_line
from odohil.errors import OdohilError
from odohil.session.exports import export_files
from odohil.session.report import load_report, write_report


def report(
    session: Annotated[Path, typer.Argument(help="The session folder (holds journal.jsonl).")],
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
) -> None:
    """Write index.html (plots inline), parameters.json and the files of odohil export to --out.

    An estimate that is not trusted, none at all, or one too imprecise to
    export (a design below the planner's minimum trials, a correction whose
    95 % interval is wider than itself) is refused (exit 3, nothing
    written) unless --force; exit 2 on a bad session or --exclude.
    """
    console = Console(stderr=True)
    try:
        data = load_report(session, parse_exclude(exclude))
    except (OdohilError, OSError) as exc:
        console.print(f"[red]error:[/red] {exc}")
        raise typer.Exit(EXIT_BAD_INPUT) from None
    outcome = data.outcome
    assert outcome is not None  # load_report always sets it
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
        extra = () if data.result is None else export_files(data.result, source=session.name)
        files = write_report(data, out, extra)
    except OSError as exc:
        console.print(f"[red]error:[/red] {exc}")
        raise typer.Exit(EXIT_BAD_INPUT) from None
    if not outcome.exportable:
        console.print("written with --force although refused without it")
    console.print(f"wrote {len(files)} files; open {out / 'index.html'}")


def register(app: typer.Typer) -> None:
    """Add ``report`` to the ``odohil`` app."""
    app.command("report")(report)
