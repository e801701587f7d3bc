"""``odohil report``: a self-contained HTML report of a session, with exports."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console

from odohil.errors import OdohilError
from odohil.session.report import load_report, write_report


def report(
    session: Annotated[Path, typer.Argument(help="The session folder (holds journal.jsonl).")],
    out: Annotated[Path, typer.Option("--out", help="Folder to write the report into (created).")],
) -> None:
    """Write index.html, SVG plots, parameters.json and odometry_covariance.yaml to --out."""
    console = Console(stderr=True)
    try:
        data = load_report(session)
        files = write_report(data, out)
    except (OdohilError, OSError) as exc:
        console.print(f"[red]error:[/red] {exc}")
        raise typer.Exit(2) from None
    if data.result is None:
        console.print(f"[yellow]no estimate yet:[/yellow] {data.problem}")
    console.print(f"wrote {len(files)} files; open {out / 'index.html'}")


def register(app: typer.Typer) -> None:
    """Add ``report`` to the ``odohil`` app."""
    app.command("report")(report)
