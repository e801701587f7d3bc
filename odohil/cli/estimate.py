"""``odohil estimate FILE|SESSION``: the four parameters from a trial file or a
session folder, with checks."""

from __future__ import annotations

import json
from enum import StrEnum
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console

from odohil import units
from odohil.cli.exclude import EXCLUDE_HELP, parse_exclude
from odohil.cli.exit_codes import EXIT_BAD_INPUT, exit_for_outcome
from odohil.cli.options import UNITS_DEFAULT, UnitsOption, unit_system
from odohil.cli.render import parameters_table
from odohil.cli.robot_option import ROBOT_HELP, robot_callback
from odohil.cli.verdict import export_refusal_lines, gaussian_line, outcome_line, verdict_line
from odohil.errors import OdohilError
from odohil.science.estimators.estimate import Method
from odohil.session.outcome import EstimateOutcome, estimate_path
from odohil.session.robot_file import load_robot_description


class MethodChoice(StrEnum):
    """The estimator."""

    robust = "robust"
    joint = "joint"
    paper = "paper"


def load_outcome(
    source: Path,
    robot: Path | None,
    exclude: frozenset[int],
    err: Console,
    method: Method = "robust",
) -> EstimateOutcome:
    """The recipe's outcome for a session folder or a trial file (a torn last
    journal record is reported on stderr and not used).

    Raises:
        OdohilError: unreadable source or a bad --exclude.
    """
    description = load_robot_description(robot) if robot is not None else None
    outcome = estimate_path(source, description, exclude, method)
    if outcome.torn is not None:
        err.print(
            f"[yellow]warning:[/yellow] {source}: the last journal record (line "
            f"{outcome.torn.line_number}) is torn and was not used: {outcome.torn.reason}",
            highlight=False,
        )
    return outcome


def register(app: typer.Typer) -> None:
    """Add ``estimate`` to the app."""

    @app.command("estimate")
    def estimate_command(
        file: Annotated[
            Path,
            typer.Argument(help="Trial file (pose rows or raw floor marks), or a session folder."),
        ],
        robot: Annotated[
            Path | None,
            typer.Option(
                "--robot",
                callback=robot_callback,
                help=ROBOT_HELP + " Needed for raw marks.",
            ),
        ] = None,
        method: Annotated[
            MethodChoice,
            typer.Option(
                "--method",
                help="robust (maximum likelihood with a per-trial outlier probability), "
                "joint (Gaussian maximum likelihood) or paper.",
            ),
        ] = MethodChoice.robust,
        exclude: Annotated[str | None, typer.Option("--exclude", help=EXCLUDE_HELP)] = None,
        as_json: Annotated[
            bool, typer.Option("--json", help="Print the result as JSON (SI).")
        ] = False,
        units_choice: UnitsOption = UNITS_DEFAULT,
    ) -> None:
        """Estimate E_R, E_T, K_theta, K_rho from a trial file or a session folder.

        Exit status 0 when the verdict is trusted, 3 when the estimate is
        printed but doubtful or failed or the trials give none (too few, or
        all left out), 2 on a bad file (every bad row listed by line) or a
        bad --exclude.
        """
        err = Console(stderr=True)
        try:
            outcome = load_outcome(file, robot, parse_exclude(exclude), err, method.value)
        except OdohilError as exc:
            err.print(f"[red]error:[/red] {exc}", highlight=False)
            raise typer.Exit(EXIT_BAD_INPUT) from exc
        status = exit_for_outcome(outcome)
        result = outcome.result
        if as_json:
            typer.echo(json.dumps(outcome.to_json_dict(), indent=2))
            raise typer.Exit(status)
        if result is None:
            Console().print(outcome_line(outcome), highlight=False)
            raise typer.Exit(status)
        ambiguous = list(outcome.ambiguous)
        flagged = outcome.flagged
        out = Console(width=max(120, Console().width))
        out.print(verdict_line(result.verdict), highlight=False)
        title = (
            f"odometry error parameters ({result.method}, {units.plural(result.n_trials, 'trial')})"
        )
        out.print(parameters_table(result, unit_system(units_choice), title))
        out.print(f"model check: {result.model_check.verdict}", highlight=False)
        out.print(f"sufficiency: {result.sufficiency.verdict}", highlight=False)
        for reason in result.sufficiency.reasons:
            out.print(f"  - {reason}", highlight=False)
        for note in result.notes:
            out.print(f"note: {note}", highlight=False)
        for line in export_refusal_lines(outcome):
            out.print(line, highlight=False)
        if result.gaussian:
            out.print(gaussian_line(result, unit_system(units_choice)), highlight=False)
        if result.excluded:
            out.print(
                f"left out (--exclude): {units.plural_noun(len(result.excluded), 'trial')} "
                + ", ".join(map(str, result.excluded))
            )
        if ambiguous:
            out.print(
                "ambiguous trials left out (two candidate poses stay plausible): "
                + ", ".join(map(str, ambiguous)),
                highlight=False,
            )
        if flagged:
            named = ", ".join(f"{trial} ({note})" for trial, note in flagged)
            out.print(f"flagged trials (pose from the marks in doubt): {named}")
        raise typer.Exit(status)
