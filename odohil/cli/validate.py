"""``odohil validate SESSION --path ...``: does the calibrated model predict a
path it was not fitted on? (odohil/session/validation.py,
odohil/science/validation.py)."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.console import Console
from rich.markup import escape
from rich.table import Table

from odohil import units
from odohil.cli.exclude import EXCLUDE_HELP, parse_exclude
from odohil.cli.exit_codes import (
    EXIT_BAD_INPUT,
    EXIT_ERROR,
    EXIT_OK,
    EXIT_UNTRUSTED,
    exit_for_outcome,
    exit_for_run,
)
from odohil.cli.options import bounded
from odohil.cli.recording_options import (
    MAX_TIME_DIFF_DEFAULT,
    MAX_TRUTH_GAP_DEFAULT,
    MIN_EDGE_REST_DEFAULT,
    MIN_REST_DEFAULT,
    ODOM_TOPIC_DEFAULT,
    TRUTH_TOPIC_DEFAULT,
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
from odohil.cli.robot_option import ROBOT_HELP, robot_callback
from odohil.cli.session_view import (
    prepared_or_exit,
    report_run,
    run_with_progress,
    say_opened,
    session_exit_codes,
)
from odohil.cli.verdict import outcome_line
from odohil.errors import (
    JournalError,
    MeasurementError,
    OdohilError,
    ParameterError,
    RobotDescriptionError,
)
from odohil.science.robot_description import RobotDescription, parse_robot_description
from odohil.science.validation import DEFAULT_ALPHA, ValidationResult
from odohil.session.lifecycle import SessionSpec, open_session, preflight
from odohil.session.plan import Plan
from odohil.session.robot_file import load_robot_description, read_robot_toml
from odohil.session.state import description_of_header, load_session
from odohil.session.validation import (
    PATH_SYNTAX,
    Calibration,
    ValidationPath,
    ValidationTrials,
    check_not_fitted,
    check_trials,
    default_folder,
    held_out_trials,
    load_calibration,
    parameter_covariance,
    parse_validation_path,
    predictions_of,
    read_path_poses,
    trials_of_session,
)

_HELP = (
    f"Test the calibrated model of SESSION on a path it was not fitted on. --path is "
    f"{PATH_SYNTAX}.\n\n"
    "SESSION is the calibration: a session folder, a trial file (forth-and-back, or a "
    "general-path trial file of `odohil import`) or a recording `odohil import` reads (with "
    "--robot and import's recording options); file:HELDOUT is likewise a trial file or a "
    "recording. A general-path calibration (turns_exact = false) predicts with its turn "
    "errors.\n\n"
    "A forth-back path is driven (--trials N, --measure fake|FILE, the port from --port or "
    "robot.toml \\[serial]) and journaled as its own validation session, by default "
    "SESSION/validation/<path>/, never mixed into the calibration; when that folder already "
    "holds a finished validation of the path, its trials are tested again without driving.\n\n"
    "A square has in-place turns and the robot protocol drives forth-and-back designs only: "
    "give the square's measured poses with --measure FILE (columns dx_m,dy_m,dtheta_rad and "
    "optionally sigma_x_m,sigma_y_m,sigma_theta_rad). file:CSV reads a trial file (pose rows, "
    "or raw distances solved with the session's robot description).\n\n"
    "Each trial's predicted mean and covariance (the measurement covariance and, by the delta "
    "method, the estimate's own covariance included) are tested by a NEES chi-square test over "
    "all trials and per axis (x, y, theta), each at --alpha/4.\n\n"
    "Exit 0 pass; 3 fail, or an untrusted calibration refused without --force; 2 bad input "
    "(nothing moved)."
)


def _bad(console: Console, message: str) -> typer.Exit:
    console.print(f"[red]error[/]: {escape(message)}", soft_wrap=True, highlight=False)
    return typer.Exit(EXIT_BAD_INPUT)


def _description(calibration: Calibration, robot: Path | None) -> tuple[RobotDescription, str, str]:
    """The robot description (from --robot, else the session's) and its TOML text."""
    if robot is None:
        state = calibration.state
        if state is None:
            raise ParameterError(
                f"--robot is needed: the calibration {calibration.outcome.source} is a file or "
                "a recording, not a session (whose robot description is journaled)"
            )
        return (
            description_of_header(state),
            str(state.header["robot_toml"]),
            str(state.header.get("robot_path") or ""),
        )
    toml = read_robot_toml(robot, ParameterError, "--robot: robot description")
    return parse_robot_description(toml, str(robot)), toml, str(robot)


def validate(
    session: Annotated[
        Path,
        typer.Argument(
            help="The calibration: a session folder, a trial file or a recording (with --robot)."
        ),
    ],
    *,
    path_text: Annotated[str, typer.Option("--path", help=PATH_SYNTAX)],
    trials: Annotated[
        int | None,
        typer.Option(
            "--trials",
            callback=bounded("plan_n"),
            help="Trials to drive (forth-back), or to use from a file (default: all rows).",
        ),
    ] = None,
    measure: Annotated[
        str | None,
        typer.Option(
            "--measure",
            help="`fake` (the fake robot's true pose), `tcp://HOST:PORT` (motion capture) "
            "or a file: a trial file for a driven path (as run), a pose file for a square.",
        ),
    ] = None,
    port: Annotated[
        str | None, typer.Option("--port", help="Serial device, pty path or pyserial URL.")
    ] = None,
    robot_file: Annotated[
        Path | None,
        typer.Option(
            "--robot", callback=robot_callback, help=ROBOT_HELP + " Default: the session's."
        ),
    ] = None,
    baud: Annotated[
        int | None, typer.Option("--baud", callback=bounded("baud"), help="Line speed.")
    ] = None,
    truth_socket: Annotated[
        str | None,
        typer.Option("--truth-socket", help="The fake robot's truth socket (--measure fake)."),
    ] = None,
    seed: Annotated[
        int, typer.Option("--seed", callback=bounded("seed"), help="Seed of the simulated tape.")
    ] = 0,
    out: Annotated[
        Path | None,
        typer.Option(
            "--out", help="Validation session folder (default SESSION/validation/<path>)."
        ),
    ] = None,
    alpha: Annotated[
        float,
        typer.Option("--alpha", help="False-rejection level of the verdict, in (0, 0.5]."),
    ] = DEFAULT_ALPHA,
    force: Annotated[
        bool, typer.Option("--force", help="Validate an estimate that is not trusted.")
    ] = False,
    exclude: Annotated[str | None, typer.Option("--exclude", help=EXCLUDE_HELP)] = None,
    as_json: Annotated[bool, typer.Option("--json", help="Print the result as JSON.")] = False,
    log_format: LogFormatOption = None,
    odom_topic: OdomTopicOption = ODOM_TOPIC_DEFAULT,
    truth_topic: TruthTopicOption = TRUTH_TOPIC_DEFAULT,
    max_time_diff: MaxTimeDiffOption = MAX_TIME_DIFF_DEFAULT,
    time_offset: TimeOffsetOption = 0.0,
    min_rest: MinRestOption = MIN_REST_DEFAULT,
    min_edge_rest: MinEdgeRestOption = MIN_EDGE_REST_DEFAULT,
    max_truth_gap: MaxTruthGapOption = MAX_TRUTH_GAP_DEFAULT,
) -> None:
    console = Console(stderr=True)
    if not (math.isfinite(alpha) and 0.0 < alpha <= 0.5):
        raise _bad(console, f"--alpha must be within (0, 0.5], got {alpha!r}")
    try:
        vpath = parse_validation_path(path_text)
        left_out = parse_exclude(exclude)
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
        given = None if robot_file is None else load_robot_description(robot_file)
        calibration = load_calibration(session, left_out, given, recording)
        description, toml, robot_path = _description(calibration, robot_file)
    except (OdohilError, OSError) as exc:
        raise _bad(console, str(exc)) from None
    outcome = calibration.outcome
    if outcome.result is None:
        console.print(outcome_line(outcome), highlight=False)
        console.print("[red]refused:[/red] the calibration gives no estimate; nothing tested.")
        raise typer.Exit(exit_for_outcome(outcome))
    result = outcome.result
    if not result.verdict.trusted and not force:
        console.print(outcome_line(outcome), highlight=False)
        console.print(
            "[red]refused:[/red] the calibration's estimate is not trusted; nothing tested. "
            "Fix its trials (or leave them out with --exclude), or pass --force."
        )
        raise typer.Exit(EXIT_UNTRUSTED)
    folder: Path | None = None
    try:
        if vpath.kind == "file":
            assert vpath.file is not None
            _no_robot(vpath, port, measure)
            measured = held_out_trials(vpath.file, description, recording)
            plan = None if calibration.state is None else calibration.state.plan
            check_not_fitted(plan, [d.forward for d in measured.designs])
        elif vpath.kind == "square":
            assert vpath.path is not None
            if port is not None or measure in (None, "fake"):
                raise ParameterError(
                    f"--path {path_text}: a square has in-place turns and the robot protocol "
                    "drives forth-and-back designs only; give the square's measured poses "
                    "with --measure FILE (no --port)"
                )
            measured = read_path_poses(Path(str(measure)), vpath.path, vpath.text)
        else:
            assert vpath.design is not None
            if calibration.state is None:
                raise ParameterError(
                    f"--path {path_text} drives the robot and journals a validation session "
                    f"beside the calibration's: {session} is no session; give the held-out "
                    "trials with --path file:HELDOUT"
                )
            check_not_fitted(calibration.state.plan, [vpath.design])
            folder = out or default_folder(session, vpath)
            measured = _drive_or_reload(
                folder,
                vpath,
                trials,
                measure,
                port,
                baud,
                truth_socket,
                seed,
                description,
                toml,
                robot_path,
                session,
                console,
            )
        if trials is not None:
            if trials > len(measured):
                raise ParameterError(
                    f"--trials {trials}: {measured.source} has {len(measured)} usable trials"
                )
            measured = measured.first(trials)
        tested = check_trials(measured, result, alpha)
    except typer.Exit:
        raise
    except (ParameterError, RobotDescriptionError, JournalError, MeasurementError) as exc:
        raise _bad(console, str(exc)) from None
    except OdohilError as exc:
        console.print(f"[red]error[/]: {escape(str(exc))}", soft_wrap=True)
        raise typer.Exit(EXIT_ERROR) from None
    data = _json(session, vpath, folder, measured, calibration, tested)
    if as_json:
        typer.echo(json.dumps(data))
    else:
        _print(data, tested, measured)
    raise typer.Exit(EXIT_OK if tested.passed else EXIT_UNTRUSTED)


def _no_robot(vpath: ValidationPath, port: str | None, measure: str | None) -> None:
    if port is not None or measure is not None:
        raise ParameterError(
            f"--path {vpath.text} reads its trials from the file: --port and --measure "
            "are not used (to drive, give --path forth-back:K,L)"
        )


def _drive_or_reload(
    folder: Path,
    vpath: ValidationPath,
    trials: int | None,
    measure: str | None,
    port: str | None,
    baud: int | None,
    truth_socket: str | None,
    seed: int,
    description: RobotDescription,
    toml: str,
    robot_path: str,
    session: Path,
    console: Console,
) -> ValidationTrials:
    """Drive a forth-back validation session in ``folder``, or re-read a finished one."""
    assert vpath.design is not None
    if (folder / "journal.jsonl").is_file():
        state = load_session(folder).state
        settings = state.header.get("settings", {})
        if settings.get("validation_path") != vpath.text or not state.finished:
            raise JournalError(
                f"{folder} holds {'another' if state.finished else 'an unfinished'} "
                "validation session: give --out NEW_FOLDER"
                + ("" if state.finished else f", or `odohil resume {folder}` first")
            )
        console.print(f"re-testing the trials journaled in {folder} (nothing driven)")
        return trials_of_session(state, source=str(folder))
    if trials is None:
        raise ParameterError("--trials N is needed to drive a validation path (N in 1..10000)")
    if measure is None:
        raise ParameterError(
            "--measure is needed to drive: `fake`, `tcp://HOST:PORT` or a trial file (CSV)"
        )
    spec = SessionSpec(
        folder, "new", Path(robot_path) if robot_path else None, robot_toml=toml,
        plan=Plan.of([(vpath.design, trials)]), measure=measure, port=port, baud=baud,
        truth_socket=truth_socket, seed=seed, purpose="validate",
        settings={"validation_of": str(session.resolve()), "validation_path": vpath.text},
    )  # fmt: skip
    with session_exit_codes(console):
        prepared = prepared_or_exit(preflight(spec), console)
        with open_session(prepared, say_opened(console)) as opened:
            console.print(f"validation session {folder}")
            console.print(f"robot: {prepared.line.describe()}", soft_wrap=True, markup=False)
            outcome = run_with_progress(console, opened)
    if outcome.status != "finished":
        report_run(console, outcome)
        raise typer.Exit(exit_for_run(outcome))
    return trials_of_session(outcome.state, source=str(folder))


def _json(
    session: Path,
    vpath: ValidationPath,
    folder: Path | None,
    measured: ValidationTrials,
    calibration: Calibration,
    tested: ValidationResult,
) -> dict[str, Any]:
    result = calibration.result
    verdict = tested.to_json_dict()
    verdict["parameter_uncertainty"] = (
        "included (delta method, the estimate's covariance)"
        if tested.parameter_uncertainty
        else "left out: the estimate's covariance is not finite"
    )
    predictions = {}
    for label, p in zip(measured.labels, predictions_of(measured, result), strict=True):
        if label not in predictions:
            predictions[label] = {"mean": p.mean.tolist(), "cov": p.cov.tolist()}
    return {
        "verdict": verdict,
        "path": vpath.text,
        "session": str(session),
        "validation_session": str(folder) if folder is not None else None,
        "source": measured.source,
        "n_trials": len(measured),
        "left_out_ambiguous": list(measured.left_out),
        "trials": [
            {
                "trial": n,
                "path": label,
                "pose_change": pose.tolist(),
                "residual": r.tolist(),
                "nees": float(e),
            }
            for n, label, pose, r, e in zip(
                measured.numbers,
                measured.labels,
                measured.poses,
                tested.residuals,
                tested.trial_nees,
                strict=True,
            )
        ],
        "prediction": predictions,
        "calibration": {
            "verdict": result.verdict.to_json_dict(),
            "parameters": {p.name: p.to_json_dict() for p in result.parameters},
            "covariance": [list(row) for row in result.covariance]
            if parameter_covariance(result) is not None
            else None,
        },
    }


def _print(data: dict[str, Any], tested: ValidationResult, measured: ValidationTrials) -> None:
    out = Console(width=max(100, Console().width))
    status = "PASS" if tested.passed else "FAIL"
    failed = tested.failed()
    text = f"validation: {status} ({units.plural(tested.n_trials, 'trial')} of {data['path']}"
    text += f"; rejected by {', '.join(failed)})" if failed else ")"
    out.print(text, highlight=False)
    for reason in tested.reasons():
        out.print(f"  {reason}", highlight=False)
    table = Table(
        title="chi-square tests (NEES: the spread; bias: the mean residual), "
        f"each at level {tested.level:g}"
    )
    for column in ("test", "statistic", "dof", "p-value", "threshold", "result"):
        table.add_column(column, justify="left" if column in ("test", "result") else "right")
    for t in tested.tests:
        table.add_row(
            t.name,
            f"{t.statistic:.4g}",
            str(t.dof),
            f"{t.p_value:.3g}",
            f"{t.threshold:.4g}",
            "pass" if t.passed else "[red]FAIL[/]",
        )
    out.print(table)
    out.print(f"parameter uncertainty: {data['verdict']['parameter_uncertainty']}", highlight=False)
    if measured.left_out:
        out.print(f"ambiguous trials left out: {', '.join(map(str, measured.left_out))}")


def register(app: typer.Typer) -> None:
    """Add ``validate`` to the ``odohil`` app."""
    app.command("validate", help=_HELP)(validate)
