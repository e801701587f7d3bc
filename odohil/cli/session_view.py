"""What run, resume, demo, validate and the wizard show of a session's
lifecycle (odohil/session/run/): the pre-flight failure, the progress
bar, how the run ended, the verdict line and the summary; the exit statuses
are odohil/cli/exit_codes.py's. Also the one place the CLI registers the
fakes' pyserial URL handlers (the only layer that may import the fakes)."""

from __future__ import annotations

import contextlib
import json
from collections.abc import Callable, Iterator, Mapping
from typing import Any, NoReturn

import typer
from rich.console import Console
from rich.markup import escape
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

from odohil import units
from odohil.cli.exit_codes import (
    EXIT_ERROR,
    EXIT_STOP_UNCONFIRMED,
    exit_for_check,
    exit_for_run,
    exit_for_signal,
)
from odohil.cli.render import bad_input, drawn, print_lines, print_said, print_verdict
from odohil.errors import (
    JournalError,
    OdohilError,
    ParameterError,
    RobotDescriptionError,
    StopUnconfirmedError,
    TrialFileError,
)
from odohil.session.journal.state import SessionState
from odohil.session.robots.registry import fake_url_schemes
from odohil.session.run import (
    Opened,
    Preflight,
    PreflightCheck,
    PreflightFailed,
    Prepared,
    RunOutcome,
    SessionSpec,
    interrupt_text,
    interrupted_before_run,
    open_session,
    preflight,
    progress_estimator,
    require,
    run_session,
)
from odohil.session.run.engine import StartCheck
from odohil.session.run.opening import CheckSeen
from odohil.session.signals import ctrl_c_in_words, signal_of, signals_raise
from odohil.session.text.outcome import outcome_notes, parameters_text
from odohil.session.text.run import MAY_STILL_MOVE, RunWatch, Said, error_said, run_ended


def register_fake_urls(port: str) -> None:
    """Register the fakes' pyserial URL handlers when ``port`` uses one (and
    only then: no fake is imported otherwise)."""
    if port.startswith(fake_url_schemes()):
        import fakes

        fakes.register_url_handlers()


def prepared_or_exit(
    checked: Preflight, console: Console, tick: CheckSeen | None = None
) -> Prepared:
    """The prepared session; else the first failed check's message and its exit
    status (nothing moved). With ``tick`` (the wizard) every check is shown
    through it. Registers the fakes' URL handlers for its port."""
    if tick is not None:
        for check in checked.checks:
            tick(check)
    try:
        prepared = require(checked)
    except PreflightFailed as exc:
        refuse(console, exc.check, tick, ticked=exc.check in checked.checks)
    for warning in prepared.warnings:
        console.print(f"[yellow]warning:[/] {escape(warning)}", soft_wrap=True)
    register_fake_urls(prepared.line.port)
    return prepared


def refuse(
    console: Console, check: PreflightCheck, tick: CheckSeen | None = None, ticked: bool = False
) -> NoReturn:
    """A failed pre-flight check: its message (the wizard: its tick, unless
    ``ticked`` already), exit by its class."""
    if tick is None:
        print_said(console, error_said(f"{check.message}; nothing moved"))
    else:
        if not ticked:
            tick(check)
        console.print("[red]Pre-flight failed: nothing was moved.[/]")
    (refused := typer.Exit(exit_for_check(check))).add_note(f"{check.message}; nothing moved")
    raise refused


def say_opened(console: Console) -> CheckSeen:
    """Told each step of opening a session: says what the pose source tells
    once it is ready (e.g. the motion-capture stream delivers)."""

    def seen(check: PreflightCheck) -> None:
        if check.name == "measurement":
            console.print(check.message, soft_wrap=True, markup=False)

    return seen


def drive(
    console: Console,
    spec: SessionSpec,
    system: units.UnitSystem,
    json_out: bool,
    say: Callable[[Opened], None],
    start_check: StartCheck | None = None,
    verdict: bool = True,
) -> RunOutcome:
    """Pre-flight, open (``say`` tells what was opened), run with a progress
    bar (what it shows: odohil/session/text/run.py :class:`RunWatch`;
    afterwards the slip check's summary) and say how the run ended (a finished
    one: its verdict line unless not ``verdict``); what escapes exits by its
    status (:func:`session_exit_codes`). The bar shows a live E_R value only,
    so the cheap incremental fit serves it instead of the recipe's robust fit
    per trial where it can (``progress_estimator``: not for a plan with
    general paths); the verdict is the recipe's (odohil/session/run)."""
    with session_exit_codes(console, json_out):
        prepared = prepared_or_exit(preflight(spec), console)
        with open_session(prepared, say_opened(console)) as opened:
            say(opened)
            bar = ProgressBar(console, opened.state)
            watch = RunWatch(bar, system)
            bar.progress.start()
            try:
                outcome = run_session(
                    opened,
                    watch,
                    estimator=progress_estimator(opened),
                    start_check=start_check or watch.show_start,
                )
            finally:
                bar.progress.stop()
                print_said(console, *watch.summary())
            if verdict or outcome.status != "finished":
                report_run(console, outcome)
    return outcome


class ProgressBar:
    """A rich progress bar of completed trials, on stderr, with lines above it:
    the :class:`~odohil.session.text.run.RunView` of a run's
    :class:`~odohil.session.text.run.RunWatch`."""

    def __init__(self, console: Console, state: SessionState) -> None:
        assert state.plan is not None
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

    def advance(self, completed: int) -> None:
        """Fill the bar to ``completed`` trials."""
        self.progress.update(self.task, completed=completed)

    def describe(self, text: str) -> None:
        """Show ``text`` beside the bar."""
        self.progress.update(self.task, description=text)

    def status(self, text: str) -> None:
        """A line above the bar."""
        self.progress.console.print(text)

    def say(self, *said: Said) -> None:
        """Lines above the bar."""
        print_said(self.progress.console, *said)


def report_run(
    console: Console,
    outcome: RunOutcome,
    continue_with: str | None = None,
    interrupted: str = "interrupted",
) -> None:
    """How the run ended: the verdict line (and why it may not be exported)
    when it finished; else what ended it and what was checked on the way out
    (odohil/session/text/run.py ``run_ended``)."""
    if outcome.status == "finished":
        print_verdict(console, outcome.estimate)
    else:
        print_said(console, *run_ended(outcome, continue_with, interrupted))


def finish(
    outcome: RunOutcome,
    json_out: bool,
    console: Console,
    extra: Mapping[str, Any] | None = None,
    truth: Mapping[str, float] | None = None,
    system: units.UnitSystem = units.DEFAULT_UNIT_SYSTEM,
    code: int | None = None,
) -> None:
    """Print the summary (a table and the notes on stdout, or one JSON object) and
    exit with the outcome's status (``code`` when given); with ``json_out`` a run
    that did not finish prints its status and partial estimate, not nothing."""
    code = exit_for_run(outcome) if code is None else code
    if json_out:
        typer.echo(json.dumps({**outcome.to_json_dict(code), **(extra or {})}))
    elif outcome.status == "finished" and (result := outcome.estimate.result) is not None:
        wide = Console(width=max(110, Console().width))
        wide.print(drawn(parameters_text(result, system, "estimate", truth)))
        print_lines(wide, outcome_notes(outcome.estimate, system))
    if code:
        raise typer.Exit(code)


@contextlib.contextmanager
def session_exit_codes(console: Console, json_out: bool = False) -> Iterator[None]:
    """Make every signal that ends a process (odohil/session/signals.py) end the
    command as Ctrl-C does, and turn what escapes into its exit status: a
    signal 128 + N, an unconfirmed stop 4, a failed pre-flight step by its
    class, a session that cannot be opened or is in use 2, any other odohil or
    OS error 1 (the robot was already stopped and the journal written below).
    With ``json_out`` an interrupt before the session ran still prints one
    JSON object saying so."""
    try:
        with signals_raise(), ctrl_c_in_words():
            yield
    except KeyboardInterrupt as exc:
        print_said(console, Said("note", "interrupted", f" ({interrupt_text(exc)})"))
        if json_out:
            typer.echo(json.dumps(interrupted_before_run(exc)))
        raise typer.Exit(exit_for_signal(signal_of(exc))) from None
    except StopUnconfirmedError as exc:
        print_said(console, Said("alarm", f"WARNING: {MAY_STILL_MOVE}", f": {exc}"))
        raise typer.Exit(EXIT_STOP_UNCONFIRMED) from None
    except PreflightFailed as exc:
        refuse(console, exc.check)
    except (ParameterError, RobotDescriptionError, TrialFileError, JournalError) as exc:
        raise bad_input(exc, console) from None  # found before anything moved
    except (OdohilError, OSError) as exc:
        print_said(console, error_said(str(exc)))
        raise typer.Exit(EXIT_ERROR) from None
