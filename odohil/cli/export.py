"""``odohil export SESSION|FILE --format F``: the estimate as a fusion stack's configuration."""

from __future__ import annotations

from enum import StrEnum
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer
from rich.console import Console

from odohil.cli.estimate import SOURCES_HELP, load_outcome
from odohil.cli.options import choices, option, robot_option
from odohil.cli.recording_options import source_options
from odohil.cli.render import bad_inputs, verdict_or_refuse
from odohil.science.exports import (
    DEFAULT_RATE_HZ,
    DEFAULT_UPDATE_MIN_A_RAD,
    DEFAULT_UPDATE_MIN_D_M,
    Linearisation,
)
from odohil.science.limits import RANGES
from odohil.science.planner import DEFAULT_SPEED_M_PER_S
from odohil.session.results.exports import FORMATS, export_text
from odohil.session.results.outcome import Selection
from odohil.session.trials.logs import ImportOptions


def _ranged(flag: str, name: str, text: str) -> object:
    return option(flag, bound=name, help=f"{text}, {RANGES[name].text()}.")


if TYPE_CHECKING:
    FormatChoice = StrEnum
else:
    FormatChoice = choices("FormatChoice", FORMATS)
"""The export formats (docs/exports.md), from the registry (results/exports.py)."""


@source_options(format_flags=("--log-format",))
def export(
    sources: Annotated[list[Path], typer.Argument(help=SOURCES_HELP)],
    fmt: Annotated[
        FormatChoice,
        option("--format", help=f"{', '.join(FORMATS)}."),
    ],
    speed: Annotated[
        float, _ranged("--speed", "speed", "Driving speed the constants are linearised at, m/s")
    ] = DEFAULT_SPEED_M_PER_S,
    rate_hz: Annotated[
        float,
        _ranged("--rate-hz", "rate_hz", "Odometry publication rate, Hz (one step = speed / rate)"),
    ] = DEFAULT_RATE_HZ,
    update_min_d: Annotated[
        float, _ranged("--update-min-d-m", "update_min_d_m", "AMCL's update distance, m")
    ] = DEFAULT_UPDATE_MIN_D_M,
    update_min_a: Annotated[
        float, _ranged("--update-min-a-rad", "update_min_a_rad", "AMCL's update angle, rad")
    ] = DEFAULT_UPDATE_MIN_A_RAD,
    out: Annotated[
        Path | None, typer.Option("--out", help="File to write (default: standard output).")
    ] = None,
    force: Annotated[
        bool,
        typer.Option(
            "--force",
            help="Export an estimate that is not trusted (the file then states its verdict).",
        ),
    ] = False,
    robot: Annotated[Path | None, robot_option(" Needed for raw marks and recordings.")] = None,
    *,
    exclude: frozenset[int],
    recording: ImportOptions,
    selection: Selection,
) -> None:
    """Write the estimate in the shape a fusion stack takes (docs/exports.md).

    An estimate that is not trusted, none at all, or one too imprecise to
    export (a design below the planner's minimum trials, a correction whose
    95 % interval is wider than itself) is refused (exit 3, nothing
    written) unless --force (no estimate is refused even then); exit 2 on
    bad input.
    """
    lin = Linearisation(speed, rate_hz, update_min_d, update_min_a)
    err = Console(stderr=True)
    outcome = load_outcome(sources, robot, exclude, err, "robust", recording, selection)
    verdict_or_refuse(err, outcome, force, None if outcome.result is None else "export it")
    result = outcome.result
    assert result is not None
    with bad_inputs(err):
        text = export_text(fmt.value, result, lin, source=sources[0].name)
        if out is not None:
            out.write_text(text, encoding="utf-8")
    if out is None:
        typer.echo(text, nl=False)
    else:
        err.print(f"wrote {out} ({fmt.value})", highlight=False)
    if not outcome.exportable:
        err.print("exported with --force although refused without it", highlight=False)
