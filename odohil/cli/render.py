"""Rich renderings shared by the commands: an error, an estimate's outcome
(verdict line and table), checks, the live estimate. The words
are the session's (odohil/session/text/outcome.py)."""

from __future__ import annotations

import contextlib
from collections.abc import Iterator, Sequence
from typing import Literal

import typer
from rich.console import Console, Group, RenderableType
from rich.markup import escape
from rich.table import Table
from rich.text import Text

from odohil import units
from odohil.cli.exit_codes import EXIT_BAD_INPUT, EXIT_UNTRUSTED
from odohil.errors import OdohilError
from odohil.science.estimators import EstimateResult
from odohil.science.estimators.verdict import Verdict
from odohil.session.journal.state import CompletedTrial
from odohil.session.results.outcome import EstimateOutcome
from odohil.session.run import PreflightCheck
from odohil.session.table_text import TableText
from odohil.session.text.outcome import (
    export_refusal_lines,
    more_trials_lines,
    outcome_line,
    outcome_notes,
    parameters_text,
    refusal_line,
    verdict_line,
)
from odohil.session.text.run import Said, error_said
from odohil.session.wizard.observables import observables_table


def drawn(text: TableText) -> Table:
    """A table of the session's words (:class:`~odohil.session.table_text.TableText`):
    numbers right-aligned, words left, a flagged cell (a failed check) in red."""
    justify: Literal["left", "center"] = "left" if text.title_left else "center"
    made = Table(title=text.title, caption=text.caption, title_justify=justify)
    for column in text.columns:
        made.add_column(column, justify="left" if column in text.words else "right")
    for row in text.rows:
        made.add_row(*(f"[red]{cell}[/]" if cell in text.flagged else cell for cell in row))
    return made


_TONES = {
    "plain": "",
    "note": "yellow",
    "error": "red",
    "alarm": "bold red",
    "title": "bold",
    "good": "green",
    "done": "bold green",
}
"""The colour of each tone of odohil/session/text/run.py's lines."""


def said_text(line: Said) -> Text:
    """A line for the operator: its head in its tone's colour, the text plain."""
    return Text.assemble((line.head, _TONES[line.tone]), line.text)


def print_said(console: Console, *said: Said, soft_wrap: bool = True) -> None:
    """Lines for the operator (:func:`said_text`), not wrapped unless not ``soft_wrap``."""
    for line in said:
        console.print(said_text(line), soft_wrap=soft_wrap)


def bad_input(exc: BaseException | str, console: Console | None = None) -> typer.Exit:
    """Print ``error: <message>`` on stderr; the exit of bad input (2) to raise."""
    print_said(console or Console(stderr=True), error_said(str(exc)))
    (refused := typer.Exit(EXIT_BAD_INPUT)).add_note(str(exc))  # for --json (odohil/cli/app.py)
    return refused


@contextlib.contextmanager
def bad_inputs(console: Console | None = None) -> Iterator[None]:
    """Within: an odohil or OS error is bad input (:func:`bad_input`, exit 2)."""
    try:
        yield
    except (OdohilError, OSError) as exc:
        raise bad_input(exc, console) from None


def torn_warning(outcome: EstimateOutcome, console: Console) -> None:
    """Say that a session journal's torn last record was not used (if so)."""
    if outcome.torn is not None:
        console.print(
            f"[yellow]warning:[/yellow] {outcome.source}: the last journal record (line "
            f"{outcome.torn.line_number}) is torn and was not used: {outcome.torn.reason}",
            highlight=False,
        )


def print_lines(console: Console, lines: Sequence[str]) -> None:
    """Plain lines (no markup, no highlighting, not wrapped)."""
    for line in lines:
        console.print(line, soft_wrap=True, markup=False, highlight=False)


def print_verdict(console: Console, outcome: EstimateOutcome) -> None:
    """The verdict line, and why the estimate may not be exported."""
    print_lines(console, [outcome_line(outcome), *export_refusal_lines(outcome)])


def print_refusal(
    console: Console, outcome: EstimateOutcome, force: str | None, undone: str
) -> None:
    """Why an estimate is not used: the verdict line, why it is not precise
    enough to export, and how to go on (``force``: what --force does, e.g.
    "export it", None when it does not help; ``undone``: "nothing written")."""
    print_verdict(console, outcome)
    line = escape(refusal_line(outcome, force, undone))
    console.print(f"[red]refused:[/red] {line}", highlight=False)


def verdict_or_refuse(
    console: Console, outcome: EstimateOutcome, force: bool, forced: str | None
) -> None:
    """The verdict line of an estimate about to be written. One that may not
    be exported is refused (the reasons; exit 3, nothing written) unless
    ``force`` and ``forced`` (what --force does; None: it does not help)."""
    if outcome.exportable or (force and forced is not None):
        print_lines(console, [outcome_line(outcome)])
        return
    print_refusal(console, outcome, forced, "nothing written")
    raise typer.Exit(EXIT_UNTRUSTED)


def print_outcome(
    out: Console, outcome: EstimateOutcome, system: units.UnitSystem, title: str | None = None
) -> None:
    """An estimate's outcome for people: the verdict line (``verdict: NO
    ESTIMATE (why)`` when there is none), the parameters table, the checks,
    notes and refusals, the Gaussian fit beside, and the trials left out."""
    print_lines(out, [outcome_line(outcome)])
    if (result := outcome.result) is not None:
        out.print(drawn(parameters_text(result, system, title)))
        checks = [f"model check: {result.model_check.verdict}"]
        print_lines(out, [*checks, f"sufficiency: {result.sufficiency.verdict}"])
    print_lines(out, outcome_notes(outcome, system))


def check_line(check: PreflightCheck) -> Text:
    """``[ok] name: detail`` (or ``[FAIL]``), coloured."""
    mark = Text("[ok]  ", style="green") if check.passed else Text("[FAIL] ", style="bold red")
    return Text.assemble(mark, (check.name, "bold"), ": ", check.message)


def estimate_panel(
    trials: Sequence[CompletedTrial],
    result: EstimateResult,
    remaining: int,
    system: units.UnitSystem = units.DEFAULT_UNIT_SYSTEM,
) -> RenderableType:
    """The live table after a trial: observables, parameters, trials still
    needed (green once the target precision is reached), model check, verdict."""
    style = "green" if result.sufficiency.sufficient else "yellow"
    return Group(
        drawn(observables_table(trials)),
        drawn(parameters_text(result, system)),
        Text("\n".join(more_trials_lines(result, remaining)), style=style),
        Text(f"Model check: {result.model_check.verdict}"),
        verdict_text(result.verdict),
    )


def verdict_text(verdict: Verdict) -> Text:
    """The verdict line, green when trusted, else red."""
    return Text(verdict_line(verdict), style="green" if verdict.trusted else "bold red")
