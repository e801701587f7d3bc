"""``odohil validate SESSION --path ...``: does the calibrated model predict a
path it was not fitted on? (odohil/session/results/validation.py,
odohil/science/validation.py)."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.console import Console

from odohil import units
from odohil.cli.exit_codes import EXIT_ERROR, EXIT_OK, EXIT_UNTRUSTED, exit_for_run
from odohil.cli.options import JsonOption, option, robot_option
from odohil.cli.recording_options import source_options
from odohil.cli.render import bad_input, bad_inputs, drawn, print_lines, print_refusal, print_said
from odohil.cli.session_view import drive
from odohil.errors import (
    JournalError,
    MeasurementError,
    OdohilError,
    ParameterError,
    RobotDescriptionError,
)
from odohil.science.estimators import EstimateResult
from odohil.science.validation import DEFAULT_ALPHA, ValidationResult
from odohil.session.commands.validate import (
    chi_square_table,
    held_out,
    lines_below_tests,
    validation_document,
    validation_setup,
    verdict_lines,
)
from odohil.session.results.validation import (
    PATH_SYNTAX,
    ValidationTrials,
    check_trials,
    trials_of_session,
)
from odohil.session.run import Opened, SessionSpec
from odohil.session.text.outcome import DETECT_HELP, outcome_line, sizing_lines
from odohil.session.text.run import error_said
from odohil.session.trials.logs import ImportOptions

_HELP = (
    f"Test the calibrated model of SESSION on a path it was not fitted on. --path is "
    f"{PATH_SYNTAX}.\n\n"
    "SESSION is the calibration: a session folder, a trial file (forth-and-back, or a "
    "general-path trial file of `odohil import`) or a recording `odohil import` reads (with "
    "--robot and import's recording options); file:HELDOUT is likewise a trial file or a "
    "recording. A general-path calibration (turns_exact = false) predicts with its turn "
    "errors.\n\n"
    "A forth-back design or a general path (square, polygon, circle; cw or ccw) is driven "
    "(--trials N, --measure fake|tcp://HOST:PORT|FILE, the port from --port or robot.toml "
    "\\[serial]; `odohil wizard --validate SESSION --path ...` with the tape) and journaled as its "
    "own validation session, by default SESSION/validation/<path>/, never mixed into the "
    "calibration; when that folder already holds a finished validation of the path, its trials "
    "are tested again without driving.\n\n"
    "A general path driven by another program: give its measured poses with --measure FILE "
    "and no --port (columns dx_m,dy_m,dtheta_rad and optionally "
    "sigma_x_m,sigma_y_m,sigma_theta_rad). file:CSV reads a trial file (pose rows, "
    "or raw distances solved with the session's robot description).\n\n"
    "Each trial's predicted mean and covariance (the measurement covariance and, by the delta "
    "method, the estimate's own covariance included) are tested by a NEES and a bias "
    "chi-square test over all trials and per axis (x, y, theta), each at --alpha/8.\n\n"
    "Exit 0 pass; 3 fail, or an untrusted calibration refused without --force; 2 bad input "
    "(nothing moved)."
)


@source_options(selection=False)
def validate(
    session: Annotated[Path, typer.Argument(help="The calibration: a session folder, a trial "
                       "file or a recording (with --robot).")],
    *,
    path_text: Annotated[str, option("--path", help=PATH_SYNTAX)],
    trials: Annotated[int | None, option("--trials", bound="plan_n", help="Trials to drive "
                      "(forth-back), or to use from a file (default: all rows).")] = None,
    detect: Annotated[str | None, option("--detect", help=DETECT_HELP)] = None,
    measure: Annotated[str | None, option("--measure", help="`fake` (the fake robot's true "
                       "pose), `tcp://HOST:PORT` (motion capture) or a file: a trial file for a "
                       "driven path (as run), a pose file for a general path without "
                       "--port.")] = None,
    port: Annotated[str | None, option("--port", help="Serial device, pty path or pyserial "
                    "URL.")] = None,
    robot_file: Annotated[Path | None, robot_option(" Default: the session's.")] = None,
    baud: Annotated[int | None, option("--baud", bound="baud", help="Line speed.")] = None,
    truth_socket: Annotated[str | None, option("--truth-socket", help="The fake robot's truth "
                            "socket (--measure fake).")] = None,
    seed: Annotated[int, option("--seed", bound="seed", help="Seed of the simulated "
                    "tape.")] = 0,
    out: Annotated[Path | None, option("--out", help="Validation session folder (default "
                   "SESSION/validation/<path>).")] = None,
    alpha: Annotated[float, option("--alpha", help="False-rejection level of the verdict, in "
                     "(0, 0.5].")] = DEFAULT_ALPHA,
    force: Annotated[bool, option("--force", help="Validate an estimate that is not "
                     "trusted.")] = False,
    as_json: JsonOption = False,
    exclude: frozenset[int],
    recording: ImportOptions,
) -> None:  # fmt: skip
    console = Console(stderr=True)
    bad = (ParameterError, RobotDescriptionError, JournalError, MeasurementError, OSError)
    with bad_inputs(console):
        setup = validation_setup(session, path_text, robot_file, exclude, recording, alpha, detect)
    outcome = setup.calibration.outcome
    result = outcome.result
    if result is None or not (result.verdict.trusted or force):
        print_refusal(console, outcome, None if result is None else "test it", "nothing tested")
        raise typer.Exit(EXIT_UNTRUSTED)
    console.print(outcome_line(outcome), highlight=False)  # the calibration's verdict

    def drive(spec: SessionSpec) -> ValidationTrials:
        line = replace(spec, port=port, baud=baud, truth_socket=truth_socket, seed=seed)
        return _drive(console, line)

    try:
        held = held_out(
            setup, session, recording, drive, trials=trials, measure=measure, port=port, out=out
        )
        if held.reread:
            console.print(f"re-testing the trials journaled in {held.folder} (nothing driven)")
        tested = check_trials(held.measured, result, alpha)
    except bad as exc:
        raise bad_input(exc, console) from None
    except OdohilError as exc:
        print_said(console, error_said(str(exc)))
        raise typer.Exit(EXIT_ERROR) from None
    data = validation_document(
        session, setup.vpath, held.folder, held.measured, setup.calibration, tested, held.sizing
    )
    if as_json:
        typer.echo(json.dumps(data))
    else:
        _print(data, tested, held.measured, result)
    raise typer.Exit(EXIT_OK if tested.passed else EXIT_UNTRUSTED)


def _drive(console: Console, spec: SessionSpec) -> ValidationTrials:
    """Drive the validation session ``spec`` (its exit status if it does not finish)."""

    def say(opened: Opened) -> None:  # --detect's count first, before anything moves
        print_lines(console, [*sizing_lines(spec.settings), f"validation session {spec.folder}"])
        console.print(f"robot: {opened.prepared.line.describe()}", soft_wrap=True, markup=False)

    outcome = drive(console, spec, units.DEFAULT_UNIT_SYSTEM, False, say, verdict=False)
    if outcome.status != "finished":
        raise typer.Exit(exit_for_run(outcome))
    return trials_of_session(outcome.state, source=str(spec.folder))


def _print(
    data: dict[str, Any],
    tested: ValidationResult,
    measured: ValidationTrials,
    calibration: EstimateResult,
) -> None:
    out = Console(width=max(100, Console().width))
    for line in verdict_lines(tested, data["path"], calibration):
        out.print(line, highlight=False)
    out.print(drawn(chi_square_table(tested)))
    for line in lines_below_tests(measured, data["verdict"]["parameter_uncertainty"]):
        out.print(line, highlight=False)


def register(app: typer.Typer) -> None:
    """Add ``validate`` to the ``odohil`` app."""
    app.command("validate", help=_HELP)(validate)
