"""``odohil simulate``: Monte Carlo trials of a forth-and-back design, written as a trial file."""

from __future__ import annotations

import os
import tempfile
import time
from pathlib import Path
from typing import Annotated, TextIO

import numpy as np
import typer
from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TaskID, TimeRemainingColumn

from odohil import units
from odohil.cli.options import (
    E_R_DEFAULT,
    E_T_DEFAULT,
    K_RHO_DEFAULT,
    K_THETA_DEFAULT,
    ERDegPerM,
    ETOption,
    KRhoM,
    KThetaDeg2PerM,
    VariantChoice,
    VariantOption,
    bounded,
    parameters_from_paper_units,
)
from odohil.errors import OdohilError
from odohil.science.limits import check_simulation_work, segments_of
from odohil.science.paths import Design, FloatArray
from odohil.science.simulator import DEFAULT_SEGMENT_M
from odohil.science.simulator import simulate as run_simulation

TRIAL_FILE_HEADER = "k,l_m,variant,dx_m,dy_m,dtheta_rad"
_PROGRESS_AFTER_S = 1.0


def write_trial_rows(stream: TextIO, design: Design, pose_change: FloatArray) -> None:
    """Write the trial file: a header, then one row per trial, floats in full (repr) precision.

    Columns: k, l_m (m), variant, dx_m, dy_m (m, start frame), dtheta_rad (rad).
    """
    stream.write(TRIAL_FILE_HEADER + "\n")
    prefix = f"{float(design.k)!r},{float(design.l_m)!r},{design.variant},"
    for dx, dy, dtheta in pose_change.tolist():
        stream.write(f"{prefix}{dx!r},{dy!r},{dtheta!r}\n")


def _write_atomically(out: Path, design: Design, pose_change: FloatArray) -> None:
    """Write to a temporary file next to ``out``, then rename: never a half-written ``out``."""
    handle, temporary = tempfile.mkstemp(prefix=f".{out.name}.", suffix=".tmp", dir=out.parent)
    try:
        with os.fdopen(handle, "w", encoding="utf-8", newline="") as stream:
            write_trial_rows(stream, design, pose_change)
        os.replace(temporary, out)
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise


class _LazyProgress:
    """A progress bar on stderr that appears only once the run has taken over a second."""

    def __init__(self, total: int, console: Console) -> None:
        self._total = total
        self._console = console
        self._started = time.monotonic()
        self._bar: Progress | None = None
        self._task = TaskID(0)

    def __call__(self, done: int) -> None:
        if self._bar is None:
            if time.monotonic() - self._started < _PROGRESS_AFTER_S:
                return
            self._bar = Progress(
                "simulating",
                BarColumn(),
                MofNCompleteColumn(),
                TimeRemainingColumn(),
                console=self._console,
                transient=True,
            )
            self._bar.start()
            self._task = self._bar.add_task("trials", total=self._total)
        self._bar.update(self._task, completed=done)

    def stop(self) -> None:
        if self._bar is not None:
            self._bar.stop()


def simulate(
    k: Annotated[
        float,
        typer.Option(
            "--k", callback=bounded("k"), help="Forth-and-back pairs k, a multiple of 1/2."
        ),
    ],
    l_m: Annotated[float, typer.Option("--l", callback=bounded("l"), help="Leg length l, metres.")],
    trials: Annotated[
        int,
        typer.Option("--trials", callback=bounded("trials"), help="Number of simulated trials."),
    ],
    out: Annotated[Path, typer.Option("--out", help="Trial file to write (CSV).")],
    variant: VariantOption = VariantChoice.turn,
    e_r: ERDegPerM = E_R_DEFAULT,
    e_t: ETOption = E_T_DEFAULT,
    k_theta: KThetaDeg2PerM = K_THETA_DEFAULT,
    k_rho: KRhoM = K_RHO_DEFAULT,
    seed: int | None = typer.Option(
        None,
        "--seed",
        callback=bounded("seed"),
        help="Random seed (a non-negative integer); default: fresh, reported.",
    ),
    segment_m: float = typer.Option(
        DEFAULT_SEGMENT_M,
        "--segment-m",
        callback=bounded("segment_m"),
        help="Largest simulated segment, metres.",
    ),
) -> None:
    """Simulate trials of k forth-and-back runs of length l and write them as a trial file.

    Each row is one trial's real pose change (dx m, dy m in the start frame,
    dtheta rad). Parameters are in the paper's units and default to the
    Nomad 150 values.
    """
    err = Console(stderr=True)
    try:
        design = Design(k, l_m, variant.value)
    except OdohilError as exc:
        raise typer.BadParameter(str(exc)) from exc
    params = parameters_from_paper_units(e_r, e_t, k_theta, k_rho)
    if trials < 1:
        raise typer.BadParameter(f"must be at least 1, got {trials}", param_hint="--trials")
    if not np.isfinite(segment_m) or segment_m <= 0:
        raise typer.BadParameter(
            f"must be a positive length in metres, got {segment_m}", param_hint="--segment-m"
        )
    if seed is not None and seed < 0:
        raise typer.BadParameter(f"must be a non-negative integer, got {seed}", param_hint="--seed")
    try:
        segments = segments_of(design.path().legs.length_m.tolist(), segment_m)
        check_simulation_work(trials, segments)
    except OdohilError as exc:
        raise typer.BadParameter(str(exc), param_hint="--trials") from exc
    if not out.parent.is_dir():
        raise typer.BadParameter(f"folder {str(out.parent)!r} does not exist", param_hint="--out")
    if out.is_dir():
        raise typer.BadParameter(f"{str(out)!r} is a folder", param_hint="--out")
    if seed is None:
        seed = int(np.random.SeedSequence().generate_state(1, dtype=np.uint64)[0] >> 1)
        err.print(f"seed {seed}", highlight=False)
    progress = _LazyProgress(trials, err)
    try:
        result = run_simulation(
            design.path(), params, trials, seed=seed, segment_m=segment_m, progress=progress
        )
    finally:
        progress.stop()
    try:
        _write_atomically(out, design, result.pose_change)
    except OSError as exc:
        raise typer.BadParameter(f"cannot write {str(out)!r}: {exc}", param_hint="--out") from exc
    err.print(
        f"wrote {units.plural(trials, 'trial')} of {design.label()} to {out}", highlight=False
    )


def register(app: typer.Typer) -> None:
    """Add ``simulate`` to the ``odohil`` app."""
    app.command("simulate")(simulate)
