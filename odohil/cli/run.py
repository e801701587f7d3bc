"""``odohil run``: an unattended calibration session on the robot.

Also the pieces ``odohil resume`` and ``odohil demo`` share: opening the
robot and its truth side channel, building the measurement source, running
the engine with a progress bar, the final summary and the exit codes
(0 done, 1 error, 130 Ctrl-C).
"""

from __future__ import annotations

import contextlib
import json
import time
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn
from rich.table import Table

from odohil.cli.exit_codes import EXIT_BAD_INPUT
from odohil.cli.options import bounded
from odohil.driver.link import DEFAULT_BAUD, open_port
from odohil.driver.robot import NomadRobot
from odohil.errors import (
    InitError,
    JournalError,
    OdohilError,
    ParameterError,
    RobotDescriptionError,
    TrialFileError,
)
from odohil.science.estimators import estimate
from odohil.science.parameters import PARAMETER_NAMES
from odohil.science.robot_description import RobotDescription
from odohil.session import state as ev
from odohil.session.engine import (
    IncrementalLiveEstimator,
    MotionSettings,
    SessionEngine,
    description_of,
    start_session,
)
from odohil.session.journal import Journal, Record
from odohil.session.preflight import check_new_session, check_trial_file
from odohil.session.sources import FakeTruthSource, MeasurementSource, TruthReader
from odohil.session.state import SessionState, session_observations

EXIT_ERROR = 1
EXIT_INTERRUPTED = 130

_PLAN_HELP = (
    'Designs and trial counts, e.g. "k=1,l=6,n=30;k=20,l=0.5,n=30" '
    "(k pairs, l metres, n trials, optional variant=turn|reverse)."
)


class SnapshotTruth:
    """The fake robot's true pose through anything with a ``truth()`` snapshot."""

    def __init__(self, owner: Any) -> None:
        self.owner = owner

    def true_pose(self) -> tuple[float, float, float]:
        """True (x m, y m, heading rad)."""
        snapshot = self.owner.truth() if hasattr(self.owner, "truth") else self.owner.snapshot()
        return (snapshot.true_x_m, snapshot.true_y_m, snapshot.true_theta_rad)


@contextlib.contextmanager
def connect(port: str, baud: int, truth_socket: str | None) -> Iterator[tuple[NomadRobot, Any]]:
    """The robot on ``port`` and its truth side channel (None when there is none).

    ``fakerobot://`` ports carry their own truth; a pty fake robot needs
    ``truth_socket``. The robot is closed (``st`` sent) on exit.
    """
    if port.startswith("fakerobot:"):
        import fakes  # noqa: F401  (registers the fakerobot:// URL handler)
    raw = open_port(port, baud)
    robot = NomadRobot.from_port(raw)
    truth: Any = None
    try:
        if truth_socket:
            from fakes.nomad.truth import TruthClient

            client = TruthClient(truth_socket)
            client.open()
            truth = client
        elif hasattr(raw, "truth"):
            truth = raw
        yield robot, truth
    finally:
        try:
            robot.close()
        finally:
            if truth is not None and hasattr(truth, "close") and truth is not raw:
                truth.close()


def make_source(
    measure: str,
    description: RobotDescription,
    truth: Any,
    seed: int,
    trial_file: str | None,
) -> MeasurementSource:
    """The measurement source named by ``measure`` (``fake`` or ``file``)."""
    if measure == "fake":
        if truth is None:
            raise InitError(
                "--measure fake needs the fake robot's truth side channel: give "
                "--truth-socket PATH (the path `odohil emulate` printed) or a fakerobot:// port"
            )
        reader: TruthReader = SnapshotTruth(truth)
        return FakeTruthSource(reader, description, seed=seed)
    if measure == "file" and trial_file:
        from odohil.session.sources import recorded_source_from_file

        return recorded_source_from_file(trial_file, description)
    raise ParameterError(f"unknown measurement source {measure!r}")


class ProgressObserver:
    """A rich progress bar of completed trials, on stderr, with notes."""

    def __init__(self, console: Console, state: SessionState) -> None:
        assert state.plan is not None
        self.console = console
        self.progress = Progress(
            TextColumn("[bold]trials"),
            BarColumn(),
            MofNCompleteColumn(),
            TimeElapsedColumn(),
            TextColumn("{task.description}"),
            console=console,
            transient=False,
        )
        self.task = self.progress.add_task(
            "", total=state.plan.n_trials, completed=len(state.completed)
        )

    def record(self, record: Record, state: SessionState) -> None:
        """Advance on each solved trial; print voids and rejections."""
        if record.kind == ev.SOLVED:
            self.progress.update(self.task, completed=len(state.completed))
        elif record.kind == ev.ESTIMATE and record.data.get("result"):
            params = record.data["result"].get("parameters", {})
            e_r = params.get("E_R", {}).get("value")
            if e_r is not None:
                self.progress.update(self.task, description=f"E_R {e_r:+.4g} rad/m")
        elif record.kind == ev.VOID:
            self.progress.console.print(
                f"trial {record.data['trial']} attempt {record.data['attempt']} void: "
                f"{record.data['reason']}"
            )
        elif record.kind == ev.MEASUREMENTS_REJECTED:
            self.progress.console.print(
                f"trial {record.data['trial']}: distances rejected, taken again: "
                f"{record.data['reason']}"
            )


@dataclass(frozen=True)
class Outcome:
    """How a session run ended: exit code and the final estimate (if any)."""

    exit_code: int
    estimate: dict[str, Any] | None


def execute(
    journal: Journal,
    state: SessionState,
    robot: NomadRobot,
    source: MeasurementSource,
    connection: Mapping[str, Any],
    console: Console,
    motion: MotionSettings | None = None,
) -> Outcome:
    """Run the engine with a progress bar; map failures to exit codes.

    The engine journals ``stopped`` and stops the robot before an error gets here.
    """
    folder = journal.folder
    observer = ProgressObserver(console, state)
    engine = SessionEngine(
        journal,
        state,
        robot,
        source,
        estimator=IncrementalLiveEstimator(),
        observer=observer,
        motion=motion,
        connection=connection,
    )
    observer.progress.start()
    try:
        final = engine.run()
    except KeyboardInterrupt:
        observer.progress.stop()
        console.print(
            f"[yellow]interrupted[/]: robot stopped, session journaled; continue with "
            f"`odohil resume {folder}`"
        )
        return Outcome(EXIT_INTERRUPTED, None)
    except OdohilError as exc:
        observer.progress.stop()
        console.print(f"[red]error[/]: {exc}")
        console.print(
            f"robot stopped, session journaled in {folder}; continue with `odohil resume {folder}`"
        )
        return Outcome(EXIT_ERROR, None)
    finally:
        observer.progress.stop()
    try:
        result = estimate(session_observations(final)).to_json_dict()
    except OdohilError as exc:
        console.print(f"[red]no estimate[/]: {exc}")
        return Outcome(EXIT_ERROR, None)
    return Outcome(0, result)


def print_summary(
    result: Mapping[str, Any], console: Console, truth: Mapping[str, float] | None = None
) -> None:
    """The estimate as a table (SI), with the true values beside when known."""
    table = Table(title=f"estimate ({result.get('method')}, {result.get('n_trials')} trials)")
    for column in ("parameter", "value", "std. error", "95 % interval", "unit"):
        table.add_column(column)
    if truth is not None:
        table.add_column("true value")
        table.add_column("inside")
    for name in PARAMETER_NAMES:
        entry = result["parameters"][name]
        low, high = entry["ci95"]
        row = [name, _num(entry["value"]), _num(entry["stderr"]), f"[{_num(low)}, {_num(high)}]"]
        row.append(entry["unit"])
        if truth is not None:
            row.append(_num(truth[name]))
            row.append("yes" if inside(entry, truth[name]) else "[red]NO[/]")
        table.add_row(*row)
    console.print(table)


def inside(entry: Mapping[str, Any], value: float) -> bool:
    """Whether ``value`` lies in the entry's 95 % interval (None: unbounded)."""
    low, high = entry["ci95"]
    return (low is None or low <= value) and (high is None or value <= high)


def _num(value: float | None) -> str:
    return "-" if value is None else f"{value:.4g}"


@contextlib.contextmanager
def session_exit_codes(console: Console) -> Iterator[None]:
    """Turn Ctrl-C into exit 130 and an odohil or OS error into its message and
    exit 1 (the robot was already stopped and the journal written below)."""
    try:
        yield
    except KeyboardInterrupt:
        console.print("[yellow]interrupted[/]")
        raise typer.Exit(EXIT_INTERRUPTED) from None
    except (ParameterError, RobotDescriptionError, TrialFileError, JournalError) as exc:
        console.print(f"[red]error[/]: {exc}")  # bad input, found before anything moved
        raise typer.Exit(EXIT_BAD_INPUT) from None
    except (OdohilError, OSError) as exc:
        console.print(f"[red]error[/]: {exc}")
        raise typer.Exit(EXIT_ERROR) from None


def default_session_folder() -> Path:
    """``odohil-session-YYYYmmdd-HHMMSS`` in the current directory."""
    return Path(f"odohil-session-{time.strftime('%Y%m%d-%H%M%S')}")


def run(
    port: Annotated[str, typer.Option("--port", help="Serial device, pty path or pyserial URL.")],
    robot_file: Annotated[Path, typer.Option("--robot", help="Robot description (TOML).")],
    plan_text: Annotated[str, typer.Option("--plan", help=_PLAN_HELP)],
    measure: Annotated[
        str,
        typer.Option(
            "--measure", help="`fake` (the fake robot's true pose) or a trial file (CSV)."
        ),
    ],
    session: Annotated[
        Path | None,
        typer.Option("--session", help="Session folder (default: odohil-session-<time> here)."),
    ] = None,
    truth_socket: Annotated[
        str | None,
        typer.Option("--truth-socket", help="The fake robot's truth socket (for --measure fake)."),
    ] = None,
    seed: Annotated[
        int,
        typer.Option(
            "--seed", callback=bounded("seed"), help="Seed of the simulated tape noise (fake)."
        ),
    ] = 0,
    baud: Annotated[
        int, typer.Option("--baud", callback=bounded("baud"), help="Line speed.")
    ] = DEFAULT_BAUD,
    json_out: Annotated[
        bool,
        typer.Option("--json", help="Print the final estimate as JSON (as estimate --json)."),
    ] = False,
) -> None:
    """Run a calibration session unattended: n trials, no prompts, journaled."""
    console = Console(stderr=True)
    folder = session or default_session_folder()
    with session_exit_codes(console):
        checked = check_new_session(plan_text, robot_file, folder)  # before anything moves
        plan, description, toml = checked.plan, checked.description, checked.toml
        kind, trial_file = ("fake", None) if measure == "fake" else ("file", measure)
        if trial_file:
            check_trial_file(trial_file, description, plan)
        settings = {
            "port": port,
            "baud": baud,
            "truth_socket": truth_socket,
            "seed": seed,
            "trial_file": str(Path(trial_file).resolve()) if trial_file else None,
        }
        with connect(port, baud, truth_socket) as (robot, truth):
            source = make_source(kind, description, truth, seed, trial_file)
            journal, state = start_session(
                folder, toml, plan, measure=kind, settings=settings, robot_path=str(robot_file)
            )
            console.print(f"session {folder}")
            with journal:
                outcome = execute(journal, state, robot, source, settings, console)
    finish(outcome, json_out, console)


def finish(
    outcome: Outcome,
    json_out: bool,
    console: Console,
    extra: Mapping[str, Any] | None = None,
    truth: Mapping[str, float] | None = None,
) -> None:
    """Print the summary (table on stdout, or JSON) and exit with the outcome's code."""
    if outcome.estimate is not None:
        if json_out:
            typer.echo(json.dumps({**outcome.estimate, **(extra or {})}))
        else:
            print_summary(outcome.estimate, Console(width=max(110, Console().width)), truth)
    if outcome.exit_code:
        raise typer.Exit(outcome.exit_code)


def resumable_description(state: SessionState) -> RobotDescription:
    """The robot description journaled in a session."""
    return description_of(state)


def register(app: typer.Typer) -> None:
    """Add ``run`` to the ``odohil`` app."""
    app.command("run")(run)
