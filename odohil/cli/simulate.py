"""``odohil simulate``: Monte Carlo trials of a forth-and-back design, written
as a trial file (odohil/session/commands/design.py writes it)."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TaskID, TimeRemainingColumn

from odohil import units
from odohil.cli.options import (
    K_OPTION,
    L_OPTION,
    SEGMENT_OPTION,
    Parameters,
    VariantChoice,
    VariantOption,
    option,
    parameters_option,
    usage_errors,
)
from odohil.science.paths import Design
from odohil.science.simulator import DEFAULT_SEGMENT_M
from odohil.session.commands import design as tools

_PROGRESS_AFTER_S = 1.0


class _LazyProgress:
    """A progress bar on stderr that appears only once the run has taken over a second."""

    def __init__(self, total: int, console: Console) -> None:
        self._total, self._console, self._started = total, console, time.monotonic()
        self._bar: Progress | None = None
        self._task = TaskID(0)

    def __call__(self, done: int) -> None:
        if self._bar is None:
            if time.monotonic() - self._started < _PROGRESS_AFTER_S:
                return
            columns = (BarColumn(), MofNCompleteColumn(), TimeRemainingColumn())
            self._bar = Progress("simulating", *columns, console=self._console, transient=True)
            self._bar.start()
            self._task = self._bar.add_task("trials", total=self._total)
        self._bar.update(self._task, completed=done)

    def stop(self) -> None:
        if self._bar is not None:
            self._bar.stop()


@parameters_option
def simulate(
    k: Annotated[float, K_OPTION],
    l_m: Annotated[float, L_OPTION],
    trials: Annotated[int, option("--trials", bound="trials", help="Simulated trials.")],
    out: Annotated[Path, typer.Option("--out", help="Trial file to write (CSV).")],
    variant: VariantOption = VariantChoice.turn,
    seed: Annotated[
        int | None,
        option("--seed", bound="seed", help="Random seed; default: fresh, reported."),
    ] = None,
    segment_m: Annotated[float, SEGMENT_OPTION] = DEFAULT_SEGMENT_M,
    as_driven_flag: Annotated[
        bool,
        typer.Option(
            "--as-driven",
            help="Trials as a plan of "
            "the design drives them (a one-way design's go out and back: every other row "
            "VARIANT-backward), so `run --measure FILE` serves that plan.",
        ),
    ] = False,
    *,
    params: Parameters,
) -> None:
    """Simulate trials of k forth-and-back runs of length l and write them as a trial file.

    Each row is one trial's real pose change (dx m, dy m in the start frame,
    dtheta rad). Parameters are in the paper's units and default to the
    Nomad 150 values.
    """
    err = Console(stderr=True)
    with usage_errors():
        design = Design(k, l_m, variant.value)
        tools.check_simulation(design, trials, segment_m, out)
    if seed is None:
        seed = tools.fresh_seed()
        err.print(f"seed {seed}", highlight=False)
    progress = _LazyProgress(trials, err)
    try:
        designs = tools.as_driven(design, trials) if as_driven_flag else (design,) * trials
        poses = tools.simulate_as_driven(designs, params, seed, segment_m, progress)
    finally:
        progress.stop()
    try:
        tools.write_simulated_trials(out, designs, poses)
    except OSError as exc:
        raise typer.BadParameter(f"cannot write {str(out)!r}: {exc}", param_hint="--out") from exc
    err.print(
        f"wrote {units.plural(trials, 'trial')} of {design.label()} to {out}", highlight=False
    )
