"""``odohil estimate FILE|SESSION``: the four parameters from a trial file or a
session folder, with checks."""

from __future__ import annotations

import json
from collections.abc import Sequence
from enum import StrEnum
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console
from rich.markup import escape

from odohil import units
from odohil.cli.exclude import EXCLUDE_HELP, parse_exclude
from odohil.cli.exit_codes import EXIT_BAD_INPUT, exit_for_outcome
from odohil.cli.options import UNITS_DEFAULT, UnitsOption, unit_system
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
from odohil.cli.render import parameters_table
from odohil.cli.robot_option import ROBOT_HELP, robot_callback
from odohil.cli.verdict import export_refusal_lines, gaussian_line, outcome_line, verdict_line
from odohil.errors import OdohilError
from odohil.session.logs import ImportOptions
from odohil.session.outcome import EstimateOutcome, Selection, estimate_source
from odohil.session.robot_file import load_robot_description


class MethodChoice(StrEnum):
    """The estimator."""

    robust = "robust"
    joint = "joint"
    paper = "paper"


def load_outcome(
    sources: Path | Sequence[Path],
    robot: Path | None,
    exclude: frozenset[int],
    err: Console,
    method: str = "robust",
    recording: ImportOptions | None = None,
    selection: Selection | None = None,
) -> EstimateOutcome:
    """The recipe's outcome for a session folder, a trial file (forth-and-back
    or general-path) or a recording (odohil/session/outcome.py
    :func:`~odohil.session.outcome.estimate_source`); a torn last journal
    record is reported on stderr and not used.

    Raises:
        OdohilError: unreadable source, a recording without --robot, a bad
            --exclude, --method or selection.
    """
    paths = [sources] if isinstance(sources, Path) else list(sources)
    description = load_robot_description(robot) if robot is not None else None
    outcome = estimate_source(paths, description, exclude, method, recording, selection)
    if outcome.torn is not None:
        err.print(
            f"[yellow]warning:[/yellow] {outcome.source}: the last journal record (line "
            f"{outcome.torn.line_number}) is torn and was not used: {outcome.torn.reason}",
            highlight=False,
        )
    return outcome


SOURCES_HELP = (
    "A session folder; a trial file (pose rows or raw floor marks; a general-path trial "
    "file of `odohil import`); or a recording `odohil import` reads (odohil log CSVs, TUM "
    "files in pairs, ROS 2 bags, optiodom run files or folders; needs --robot)."
)


def register(app: typer.Typer) -> None:
    """Add ``estimate`` to the app."""

    @app.command("estimate")
    def estimate_command(
        sources: Annotated[list[Path], typer.Argument(help=SOURCES_HELP)],
        robot: Annotated[
            Path | None,
            typer.Option(
                "--robot",
                callback=robot_callback,
                help=ROBOT_HELP + " Needed for raw marks and recordings; its \\[robot] "
                "turns_exact = false fits the turn errors e_turn (and K_spin) on general paths.",
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
        """Estimate E_R, E_T, K_theta, K_rho (and a differential drive's e_turn,
        K_spin) from a session folder, a trial file or a recording.

        Exit status 0 when the verdict is trusted, 3 when the estimate is
        printed but doubtful or failed or the trials give none (too few, or
        all left out), 2 on a bad file (every bad row listed by line) or a
        bad --exclude.
        """
        err = Console(stderr=True)
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
            outcome = load_outcome(
                sources,
                robot,
                parse_exclude(exclude),
                err,
                method.value,
                recording,
                Selection(family, direction),
            )
        except OdohilError as exc:
            err.print(f"[red]error:[/red] {escape(str(exc))}", highlight=False)
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
