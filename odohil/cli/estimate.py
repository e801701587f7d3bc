"""``odohil estimate FILE|SESSION``: the four parameters from a trial file or a
session folder, with checks."""

from __future__ import annotations

import json
from enum import StrEnum
from pathlib import Path
from typing import Annotated

import numpy as np
import typer
from rich.console import Console

from odohil import units
from odohil.cli.exclude import EXCLUDE_HELP, check_exclude, parse_exclude
from odohil.cli.exit_codes import EXIT_BAD_INPUT, EXIT_OK, EXIT_UNTRUSTED
from odohil.cli.options import UNITS_DEFAULT, UnitsOption, unit_system
from odohil.cli.render import parameters_table
from odohil.cli.robot_option import ROBOT_HELP, robot_callback, turns_exact_of
from odohil.cli.verdict import gaussian_line, verdict_line
from odohil.errors import OdohilError
from odohil.science.estimators import Observation, estimate
from odohil.session.robot_file import load_robot_description
from odohil.session.state import load_session, session_trials
from odohil.session.trial_files import Trial, TrialSet, read_trials


class MethodChoice(StrEnum):
    """The estimator."""

    robust = "robust"
    joint = "joint"
    paper = "paper"


def observation_of(trial: Trial, position: int = 0) -> Observation:
    """A trial-file row as the estimators see it; numbered by the trial's own
    number (sessions) or its 1-based ``position`` among the rows."""
    cov = trial.pose_cov if trial.pose_cov is not None else np.zeros((3, 3))
    number = trial.number if trial.number is not None else position + 1
    return Observation(trial.design, trial.pose_change, cov, line=trial.line, trial=number)


def _load(source: Path, robot: Path | None, err: Console) -> TrialSet:
    """The trials of a trial file, or the completed trials of a session folder
    (a torn last journal record is reported on stderr and not used)."""
    if source.is_dir():
        loaded = load_session(source)
        if loaded.torn is not None:
            err.print(
                f"[yellow]warning:[/yellow] {source}: the last journal record (line "
                f"{loaded.torn.line_number}) is torn and was not used: {loaded.torn.reason}",
                highlight=False,
            )
        return session_trials(loaded.state, source=str(source))
    description = load_robot_description(robot) if robot is not None else None
    return read_trials(source, description)


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
        printed but doubtful or failed, 2 on a bad file (every bad row listed
        by line), a bad --exclude, or too few trials.
        """
        err = Console(stderr=True)
        try:
            left_out = parse_exclude(exclude)
            trials = _load(file, robot, err)
            if len(trials) == 0:
                raise OdohilError(f"{file}: no trials")
            # a file's rows are numbered by position, ambiguous rows included
            rows = sorted((*trials.trials, *trials.ambiguous), key=lambda t: t.line)
            position = {t.line: i for i, t in enumerate(rows)}
            observations = [observation_of(t, position[t.line]) for t in trials.trials]
            ambiguous = [
                t.number if t.number is not None else position[t.line] + 1 for t in trials.ambiguous
            ]
            check_exclude(left_out, [o.trial for o in observations if o.trial is not None])
            result = estimate(
                observations,
                method.value,
                exclude=left_out,
                ambiguous=ambiguous,
                turns_exact=turns_exact_of(file, robot),
            )
        except OdohilError as exc:
            err.print(f"[red]error:[/red] {exc}", highlight=False)
            raise typer.Exit(EXIT_BAD_INPUT) from exc
        flagged = trials.flagged()
        status = EXIT_OK if result.verdict.trusted else EXIT_UNTRUSTED
        if as_json:
            data = result.to_json_dict()
            data["flagged_trials"] = [
                o.trial for o, t in zip(observations, trials.trials, strict=True) if t.flagged
            ]
            data["ambiguous_trials"] = ambiguous
            typer.echo(json.dumps(data, indent=2))
            raise typer.Exit(status)
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
            named = ", ".join(
                f"{o.trial} ({t.note})"
                for o, t in zip(observations, trials.trials, strict=True)
                if t.flagged
            )
            out.print(f"flagged trials (pose from the marks in doubt): {named}")
        raise typer.Exit(status)
