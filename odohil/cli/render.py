"""Rich renderings shared by interactive commands: checks, live estimate, motion progress."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from rich.console import Console, Group, RenderableType
from rich.progress import BarColumn, Progress, TaskID, TextColumn, TimeElapsedColumn
from rich.table import Table
from rich.text import Text

from odohil import units
from odohil.driver.odometry import OdometrySample
from odohil.science.observables import observables
from odohil.science.parameters import PAPER_UNITS, PARAMETER_NAMES
from odohil.science.paths import Design, Leg, Turn
from odohil.session.report import to_paper
from odohil.session.state import CompletedTrial


@dataclass(frozen=True)
class Check:
    """One pre-flight check: its name, whether it passed, and what was found."""

    name: str
    ok: bool
    detail: str


def check_line(check: Check) -> Text:
    """``[ok] name: detail`` (or ``[FAIL]``), coloured."""
    mark = Text("[ok]  ", style="green") if check.ok else Text("[FAIL] ", style="bold red")
    return Text.assemble(mark, (check.name, "bold"), ": ", check.detail)


def _unwrapped(
    angles: np.ndarray[Any, np.dtype[np.float64]],
) -> np.ndarray[Any, np.dtype[np.float64]]:
    centre = math.atan2(float(np.sin(angles).mean()), float(np.cos(angles).mean()))
    return np.asarray(centre + (angles - centre + math.pi) % (2 * math.pi) - math.pi)


def observables_table(trials: Sequence[CompletedTrial]) -> Table:
    """phi1..phi5 of every design with at least two completed trials."""
    table = Table(title="Observables per design", title_justify="left")
    for column in ("design", "n", "phi1 deg", "phi2 deg^2", "phi3 mm", "phi4 mm", "phi5 mm^2"):
        table.add_column(column, justify="left" if column == "design" else "right")
    by_design: dict[Design, list[CompletedTrial]] = {}
    for trial in trials:
        by_design.setdefault(trial.design, []).append(trial)
    for design, members in by_design.items():
        if len(members) < 2:
            table.add_row(design.label(), str(len(members)), "needs 2 trials", "", "", "", "")
            continue
        poses = np.array([t.pose_change for t in members], dtype=np.float64)
        poses[:, 2] = _unwrapped(poses[:, 2])
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


def parameters_table(result: Mapping[str, Any]) -> Table:
    """The four parameters with standard errors, paper units, from an estimate's JSON object."""
    table = Table(
        title=f"Estimate after {result.get('n_trials', '?')} trials", title_justify="left"
    )
    for column in ("parameter", "estimate", "std. error", "unit"):
        table.add_column(column, justify="left" if column in ("parameter", "unit") else "right")
    params = result.get("parameters", {})
    for name in PARAMETER_NAMES:
        entry = params.get(name, {})
        table.add_row(
            name,
            _paper(name, entry.get("value")),
            _paper(name, entry.get("stderr")),
            PAPER_UNITS[name],
        )
    return table


def _paper(name: str, value: float | None) -> str:
    if value is None or not math.isfinite(value):
        return "undetermined"
    return f"{to_paper(name, float(value)):.4g}"


def more_trials_text(result: Mapping[str, Any], remaining_in_plan: int) -> Text:
    """How many more trials reach the target precision (the sufficiency check)."""
    suff = result.get("sufficiency", {})
    if suff.get("sufficient"):
        return Text("Target precision reached for every parameter.", style="green")
    lines = [str(suff.get("verdict", "precision target not reached"))]
    # One suggestion per parameter and design: the design needs the largest.
    needed: dict[str, int | None] = {}
    for s in suff.get("suggestions", []):
        design, more = str(s.get("design")), s.get("more_trials")
        if design not in needed or (
            needed[design] is not None and (more is None or more > needed[design])
        ):
            needed[design] = more
    for design, more in needed.items():
        lines.append(
            f"  {design}: "
            + ("cannot reach it alone" if more is None else f"{more} more trials reach the target")
        )
    lines.append(f"  ({remaining_in_plan} trials remain in the plan)")
    return Text("\n".join(lines), style="yellow")


def estimate_panel(
    trials: Sequence[CompletedTrial], result: Mapping[str, Any], remaining: int
) -> RenderableType:
    """The live table after a trial: observables, parameters, trials still needed."""
    check = result.get("model_check", {})
    verdict = Text(f"Model check: {check.get('verdict', 'n/a')}")
    return Group(
        observables_table(trials),
        parameters_table(result),
        more_trials_text(result, remaining),
        verdict,
        verdict_text(result),
    )


def verdict_text(result: Mapping[str, Any]) -> Text:
    """``Verdict: trusted`` (green) or ``Verdict: doubtful: reasons`` (red)."""
    verdict = result.get("verdict", {})
    status = str(verdict.get("status", "n/a"))
    reasons = "; ".join(str(r) for r in verdict.get("reasons", []))
    style = "green" if status == "trusted" else "bold red"
    return Text(f"Verdict: {status}" + (f": {reasons}" if reasons else ""), style=style)


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

    @property
    def active(self) -> bool:
        """Whether a motion is being shown."""
        return self._progress is not None

    def start(self, design: Design) -> None:
        """Show a new motion of ``design``."""
        self.stop()
        self._steps = design.path().steps
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
