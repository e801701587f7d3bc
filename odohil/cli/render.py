"""Rich renderings shared by the commands: an error, an estimate's outcome
(verdict line and table), checks, live estimate, motion progress."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np
import typer
from rich.console import Console, Group, RenderableType
from rich.markup import escape
from rich.progress import BarColumn, Progress, TaskID, TextColumn, TimeElapsedColumn
from rich.table import Table
from rich.text import Text

from odohil import units
from odohil.cli.exit_codes import EXIT_BAD_INPUT
from odohil.cli.verdict import export_refusal_lines, gaussian_line, outcome_line, verdict_line
from odohil.driver.odometry import OdometrySample
from odohil.science.estimators import EstimateResult, ParameterEstimate
from odohil.science.estimators.verdict import Verdict
from odohil.science.grouping import by_design
from odohil.science.observables import observables
from odohil.science.paths import Design, Leg, Turn
from odohil.session.lifecycle import PreflightCheck
from odohil.session.outcome import EstimateOutcome
from odohil.session.state import CompletedTrial


def table(
    title: str, columns: Sequence[str], left: Sequence[str] = (), caption: str | None = None
) -> Table:
    """A table of ``columns``, right-aligned (numbers) but for those in ``left``."""
    made = Table(title=title, caption=caption)
    for column in columns:
        made.add_column(column, justify="left" if column in left else "right")
    return made


def bad_input(exc: BaseException | str, console: Console | None = None) -> typer.Exit:
    """Print ``error: <message>`` on stderr; the exit of bad input (2) to raise."""
    (console or Console(stderr=True)).print(
        f"[red]error:[/red] {escape(str(exc))}", soft_wrap=True, highlight=False
    )
    return typer.Exit(EXIT_BAD_INPUT)


def torn_warning(outcome: EstimateOutcome, console: Console) -> None:
    """Say that a session journal's torn last record was not used (if so)."""
    if outcome.torn is not None:
        console.print(
            f"[yellow]warning:[/yellow] {outcome.source}: the last journal record (line "
            f"{outcome.torn.line_number}) is torn and was not used: {outcome.torn.reason}",
            highlight=False,
        )


def print_refusal(
    console: Console, outcome: EstimateOutcome, force: str | None, undone: str
) -> None:
    """Why an estimate is not used: the verdict line, why it is not precise
    enough to export, and how to go on (``force``: what --force does, e.g.
    "export it", None when it does not help; ``undone``: "nothing written")."""
    console.print(outcome_line(outcome), highlight=False)
    for line in export_refusal_lines(outcome):
        console.print(line, highlight=False)
    what = "the estimate is not " + ("precise enough" if outcome.trusted else "trusted")
    if outcome.result is None:
        what = "there is no estimate"
    console.print(
        f"[red]refused:[/red] {what}; {undone}. Fix the trials (or leave them out with "
        "--exclude N,...), add trials"
        + (f", or pass --force to {force} with the verdict stated." if force else "."),
        highlight=False,
    )


def print_outcome(
    out: Console, outcome: EstimateOutcome, system: units.UnitSystem, title: str | None = None
) -> None:
    """An estimate's outcome for people: the verdict line (``verdict: NO
    ESTIMATE (why)`` when there is none), the parameters table, the checks,
    notes and refusals, the Gaussian fit beside, and the trials left out."""
    out.print(outcome_line(outcome), highlight=False)
    result = outcome.result
    if result is None:
        return
    out.print(parameters_table(result, system, title))
    out.print(f"model check: {result.model_check.verdict}", highlight=False)
    out.print(f"sufficiency: {result.sufficiency.verdict}", highlight=False)
    lines = [f"  - {reason}" for reason in result.sufficiency.reasons]
    lines += [f"note: {note}" for note in result.notes] + export_refusal_lines(outcome)
    if result.gaussian:
        lines.append(gaussian_line(result, system))
    if result.excluded:
        lines.append(
            f"left out (--exclude): {units.plural_noun(len(result.excluded), 'trial')} "
            + ", ".join(map(str, result.excluded))
        )
    if outcome.ambiguous:
        lines.append(
            "ambiguous trials left out (two candidate poses stay plausible): "
            + ", ".join(map(str, outcome.ambiguous))
        )
    if outcome.flagged:
        named = ", ".join(f"{trial} ({note})" for trial, note in outcome.flagged)
        lines.append(f"flagged trials (pose from the marks in doubt): {named}")
    for line in lines:
        out.print(line, highlight=False)


def check_line(check: PreflightCheck) -> Text:
    """``[ok] name: detail`` (or ``[FAIL]``), coloured."""
    mark = Text("[ok]  ", style="green") if check.passed else Text("[FAIL] ", style="bold red")
    return Text.assemble(mark, (check.name, "bold"), ": ", check.message)


def observables_table(trials: Sequence[CompletedTrial]) -> Table:
    """phi1..phi5 of every design with at least two completed trials."""
    table = Table(title="Observables per design", title_justify="left")
    for column in ("design", "n", "phi1 deg", "phi2 deg^2", "phi3 mm", "phi4 mm", "phi5 mm^2"):
        table.add_column(column, justify="left" if column == "design" else "right")
    for design, members in by_design(trials).items():
        if len(members) < 2:
            table.add_row(design.label(), str(len(members)), "needs 2 trials", "", "", "", "")
            continue
        poses = np.array([t.pose_change for t in members], dtype=np.float64)
        poses[:, 2] = units.angle_near(poses[:, 2], units.circular_mean(poses[:, 2]))
        phi = observables(poses)
        table.add_row(
            design.label(),
            str(phi.n_trials),
            f"{units.radians_to_degrees(phi.phi1):.4g}",
            f"{units.rad2_to_deg2(phi.phi2):.3g}",
            f"{1e3 * phi.phi3:.3g}",
            f"{1e3 * phi.phi4:.3g}",
            f"{1e6 * phi.phi5:.3g}",
        )
    return table


def parameters_table(
    result: EstimateResult,
    system: units.UnitSystem = units.DEFAULT_UNIT_SYSTEM,
    title: str | None = None,
    truth: Mapping[str, float] | None = None,
) -> Table:
    """The four parameters with standard errors and 95 % intervals in
    ``system``'s units; with ``truth`` (SI values by name) a truth column in
    the same units and whether the interval holds it."""
    table = Table(
        title=title or f"Estimate after {units.plural(result.n_trials, 'trial')}",
        title_justify="left",
    )
    columns = ["parameter", "estimate", "std. error", "95 % interval", "unit"]
    if truth is not None:
        columns += ["truth", "truth inside"]
    for column in columns:
        table.add_column(column, justify="left" if column in ("parameter", "unit") else "right")
    for p in result.parameters:
        low, high = p.ci95
        row = [
            p.name,
            number_text(p.name, p.value, system),
            number_text(p.name, p.stderr, system, digits=2),
            f"[{number_text(p.name, low, system)}, {number_text(p.name, high, system)}]",
            units.unit_column(p.name, system),
        ]
        if truth is not None:
            row.append(number_text(p.name, truth[p.name], system))
            row.append("yes" if inside(p, truth[p.name]) else "[red]NO[/]")
        table.add_row(*row)
    return table


def number_text(name: str, value_si: float, system: units.UnitSystem, digits: int = 4) -> str:
    """A parameter's value (SI) as text in ``system``'s units, without the unit;
    "-" when not finite (undetermined, or an unbounded interval end)."""
    if not math.isfinite(value_si):
        return "-"
    return f"{units.parameter_in(name, value_si, system):.{digits}g}"


def parameters_line(values_si: Mapping[str, float], system: units.UnitSystem) -> str:
    """``E_R = -1 deg/m, E_T = -0.05, K_theta = 0.3 deg^2/m, K_rho = 0.0009 m``."""
    return ", ".join(
        f"{name} = "
        + units.with_unit(number_text(name, value, system), units.parameter_unit(name, system))
        for name, value in values_si.items()
    )


def inside(entry: ParameterEstimate, value: float) -> bool:
    """Whether ``value`` lies in the entry's 95 % interval (a non-finite end: unbounded)."""
    low, high = entry.ci95
    return (not math.isfinite(low) or low <= value) and (not math.isfinite(high) or value <= high)


def more_trials_text(result: EstimateResult, remaining_in_plan: int) -> Text:
    """How many more trials reach the target precision (the sufficiency check)."""
    suff = result.sufficiency
    if suff.sufficient:
        return Text("Target precision reached for every parameter.", style="green")
    lines = [suff.verdict or "precision target not reached"]
    # One suggestion per parameter and design: the design needs the largest.
    needed: dict[str, int | None] = {}
    for s in suff.suggestions:
        design, more = s.design_label, s.more_trials
        if design not in needed or (
            (known := needed[design]) is not None and (more is None or more > known)
        ):
            needed[design] = more
    for design, more in needed.items():
        lines.append(
            f"  {design}: "
            + (
                "cannot reach it alone"
                if more is None
                else f"{units.plural(more, 'more trial')} "
                f"{'reaches' if more == 1 else 'reach'} the target"
            )
        )
    lines.append(
        f"  ({units.plural(remaining_in_plan, 'trial')} "
        f"{'remains' if remaining_in_plan == 1 else 'remain'} in the plan)"
    )
    return Text("\n".join(lines), style="yellow")


def estimate_panel(
    trials: Sequence[CompletedTrial],
    result: EstimateResult,
    remaining: int,
    system: units.UnitSystem = units.DEFAULT_UNIT_SYSTEM,
) -> RenderableType:
    """The live table after a trial: observables, parameters, trials still needed."""
    return Group(
        observables_table(trials),
        parameters_table(result, system),
        more_trials_text(result, remaining),
        Text(f"Model check: {result.model_check.verdict}"),
        verdict_text(result.verdict),
    )


def verdict_text(verdict: Verdict) -> Text:
    """The verdict line (:func:`~odohil.cli.verdict.verdict_line`), green when
    trusted, else red."""
    return Text(verdict_line(verdict), style="green" if verdict.trusted else "bold red")


class MotionProgress:
    """A progress bar of one forth-and-back motion with the live encoder pose.

    Progress counts steps (legs and turns), each filled by how far its
    distance or angle has been covered.
    """

    def __init__(self, console: Console) -> None:
        self.console = console
        self._progress: Progress | None = None
        self._task: TaskID | None = None
        self._steps: tuple[Leg | Turn, ...] = ()
        self._step = 0
        self._step_start: OdometrySample | None = None

    @property
    def active(self) -> bool:
        """Whether a motion is being shown."""
        return self._progress is not None

    def start(self, design: Design) -> None:
        """Show a new motion of ``design``."""
        self.stop()
        self._steps = design.path().steps
        self._step, self._step_start = 0, None
        self._progress = Progress(
            TextColumn("driving {task.description}"),
            BarColumn(),
            TextColumn("{task.percentage:>3.0f}%"),
            TimeElapsedColumn(),
            TextColumn("{task.fields[pose]}"),
            console=self.console,
            refresh_per_second=8,
        )
        self._task = self._progress.add_task(design.label(), total=len(self._steps), pose="")
        self._progress.start()

    def sample(self, sample: OdometrySample) -> None:
        """An encoder sample of the motion: the first is taken before the first
        step; a step ends at the first sample that shows the robot at rest."""
        if self._step_start is None:
            self._step_start = sample
            return
        self.update(self._step, self._step_start, sample)
        if not sample.moving:
            self._step, self._step_start = self._step + 1, sample

    def update(self, step: int, start: OdometrySample | None, sample: OdometrySample) -> None:
        """A new encoder sample in step ``step`` (0-based) that began at ``start``."""
        if self._progress is None or self._task is None or step >= len(self._steps):
            return
        fraction = 0.0
        if start is not None:
            item = self._steps[step]
            if isinstance(item, Leg) and item.length_m > 0:
                moved = math.hypot(sample.x_m - start.x_m, sample.y_m - start.y_m)
                fraction = moved / abs(item.length_m)
            elif isinstance(item, Turn) and item.angle_rad != 0:
                turned = abs(units.wrap_angle(sample.theta_rad - start.theta_rad))
                fraction = turned / min(abs(item.angle_rad), math.pi)
        pose = (
            f"x={sample.x_m:+.3f} m y={sample.y_m:+.3f} m "
            f"heading={math.degrees(sample.theta_rad):6.1f} deg"
        )
        self._progress.update(self._task, completed=step + min(1.0, fraction), pose=pose)

    def stop(self) -> None:
        """Close the bar (idempotent)."""
        if self._progress is not None:
            self._progress.stop()
        self._progress = None
        self._task = None
