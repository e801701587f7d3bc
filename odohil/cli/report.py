"""``odohil report``: a self-contained HTML report of a session, with exports."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console

from odohil.cli.exclude import EXCLUDE_HELP, check_exclude, parse_exclude
from odohil.cli.exit_codes import EXIT_BAD_INPUT, EXIT_UNTRUSTED
from odohil.cli.verdict import verdict_line
from odohil.errors import OdohilError
from odohil.session.exports import export_files
from odohil.session.report import load_report, write_report
from odohil.session.state import load_session


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

    An estimate that is not trusted is refused (exit 3, nothing written)
    unless --force; exit 2 on a bad session or --exclude.
    """
    console = Console(stderr=True)
    try:
        left_out = parse_exclude(exclude)
        if left_out:
            completed = load_session(session).state.completed
            check_exclude(left_out, [t.trial for t in completed])
        data = load_report(session, left_out)
    except (OdohilError, OSError) as exc:
        console.print(f"[red]error:[/red] {exc}")
        raise typer.Exit(EXIT_BAD_INPUT) from None
    if data.result is not None and not data.result.verdict.trusted and not force:
        console.print(verdict_line(data.result.verdict), highlight=False)
        console.print(
            "[red]refused:[/red] the estimate is not trusted; nothing written. Fix the "
            "trials (or leave them out with --exclude N,...), or pass --force to write the "
            "report with the verdict stated in it."
        )
        raise typer.Exit(EXIT_UNTRUSTED)
    try:
        extra = () if data.result is None else export_files(data.result, source=session.name)
        files = write_report(data, out, extra)
    except OSError as exc:
        console.print(f"[red]error:[/red] {exc}")
        raise typer.Exit(EXIT_BAD_INPUT) from None
    if data.result is None:
        console.print(f"[yellow]no estimate yet:[/yellow] {data.problem}")
    elif not data.result.verdict.trusted:
        console.print(verdict_line(data.result.verdict) + " (written with --force)")
    console.print(f"wrote {len(files)} files; open {out / 'index.html'}")


def register(app: typer.Typer) -> None:
    """Add ``report`` to the ``odohil`` app."""
    app.command("report")(report)
