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
from rich.table import Table

from odohil import units
from odohil.errors import OdohilError
from odohil.science.estimators import EstimateResult, Observation, estimate
from odohil.science.parameters import PAPER_UNITS
from odohil.session.robot_file import load_robot_description
from odohil.session.state import load_session, session_trials
from odohil.session.trial_files import Trial, TrialSet, read_trials


class MethodChoice(StrEnum):
    """The estimator."""

    joint = "joint"
    paper = "paper"


def observation_of(trial: Trial) -> Observation:
    """A trial-file row as the estimators see it."""
    cov = trial.pose_cov if trial.pose_cov is not None else np.zeros((3, 3))
    return Observation(trial.design, trial.pose_change, cov, line=trial.line)


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


def _paper(name: str, value: float) -> float:
    if name == "E_R":
        return units.rad_per_m_to_deg_per_m(value)
    if name == "K_theta":
        return units.rad2_per_m_to_deg2_per_m(value)
    return value


def _table(result: EstimateResult) -> Table:
    table = Table(title=f"odometry error parameters ({result.method}, {result.n_trials} trials)")
    for column in ("parameter", "value", "stderr", "95% CI", "unit", "value (SI)", "stderr (SI)"):
        table.add_column(column, justify="left" if column in ("parameter", "unit") else "right")
    for p in result.parameters:
        lo, hi = (_paper(p.name, v) for v in p.ci95)
        table.add_row(
            p.name,
            f"{_paper(p.name, p.value):.4g}",
            f"{_paper(p.name, p.stderr):.2g}",
            f"[{lo:.4g}, {hi:.4g}]",
            PAPER_UNITS[p.name],
            f"{p.value:.4g} {p.unit}",
            f"{p.stderr:.2g}",
        )
    return table


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
            typer.Option("--robot", help="Robot description (TOML); needed for raw marks."),
        ] = None,
        method: Annotated[
            MethodChoice, typer.Option("--method", help="joint (maximum likelihood) or paper.")
        ] = MethodChoice.joint,
        as_json: Annotated[bool, typer.Option("--json", help="Print the result as JSON.")] = False,
    ) -> None:
        """Estimate E_R, E_T, K_theta, K_rho from a trial file or a session folder.

        Exit status 2 on a bad file (every bad row listed by line) or too few trials.
        """
        err = Console(stderr=True)
        try:
            trials = _load(file, robot, err)
            if len(trials) == 0:
                raise OdohilError(f"{file}: no trials")
            result = estimate([observation_of(t) for t in trials.trials], method.value)
        except OdohilError as exc:
            err.print(f"[red]error:[/red] {exc}", highlight=False)
            raise typer.Exit(2) from exc
        flagged = trials.flagged()
        if as_json:
            data = result.to_json_dict()
            data["flagged_lines"] = [t.line for t in flagged]
            data["ambiguous_lines"] = [t.line for t in trials.ambiguous]
            typer.echo(json.dumps(data, indent=2))
            return
        out = Console(width=max(120, Console().width))
        out.print(_table(result))
        out.print(f"model check: {result.model_check.verdict}", highlight=False)
        out.print(f"sufficiency: {result.sufficiency.verdict}", highlight=False)
        for reason in result.sufficiency.reasons:
            out.print(f"  - {reason}", highlight=False)
        for note in result.notes:
            out.print(f"note: {note}", highlight=False)
        if trials.ambiguous:
            left_out = ", ".join(str(t.line) for t in trials.ambiguous)
            out.print(
                f"ambiguous trials left out (two candidate poses stay plausible), lines: "
                f"{left_out}",
                highlight=False,
            )
        if flagged:
            lines = ", ".join(f"{t.line} ({t.note})" for t in flagged)
            out.print(f"flagged trials (pose from the marks in doubt), lines: {lines}")
