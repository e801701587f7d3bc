"""``odohil wizard``: the operator's guide beside the robot, one trial at a time.

Pre-flight checks first (nothing moves until all pass); then per trial: mark
the floor, watch the motion, type the tape distances (checked, re-asked with
the reason), see the live estimate. Ctrl-C (or SIGTERM, SIGHUP, SIGQUIT)
stops the robot, waits for it to report that it stopped, journals and exits
128 + N; if the stop cannot be confirmed it says the robot may still be
moving and exits 4. A second Ctrl-C before the engine's stop has begun sends
one ``st`` and exits at once (4 unless the robot confirmed the stop); during
the stop itself (at most 2 s) it is held. The session is locked before the
port is opened; one in use is refused (exit 2). Running the wizard again on
the same ``--session`` continues where the journal stops.
"""

from __future__ import annotations

import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console
from rich.progress import BarColumn, Progress, TaskID, TextColumn, TimeElapsedColumn

from odohil import units
from odohil.cli.exit_codes import (
    EXIT_BAD_INPUT,
    EXIT_INTERRUPTED,
    EXIT_OK,
    EXIT_STOP_UNCONFIRMED,
    EXIT_UNTRUSTED,
    exit_for_outcome,
    exit_for_run,
    exit_for_signal,
)
from odohil.cli.options import (
    UNITS_DEFAULT,
    AllowTurnsOption,
    BaudOption,
    PortOption,
    UnitsOption,
    option,
    robot_option,
    unit_system,
)
from odohil.cli.render import (
    bad_inputs,
    check_line,
    estimate_panel,
    print_lines,
    print_refusal,
    print_said,
    print_verdict,
    said_text,
)
from odohil.cli.session_view import prepared_or_exit, refuse, report_run
from odohil.driver.odometry import OdometrySample
from odohil.science.estimators import EstimateResult
from odohil.science.paths import Drivable
from odohil.science.planner import DEFAULT_MAX_LEG_M
from odohil.session.journal.state import CompletedTrial, SessionState
from odohil.session.results.validation import PATH_SYNTAX
from odohil.session.run import (
    Opened,
    PreflightCheck,
    PreflightFailed,
    SessionSpec,
    final_estimate,
    open_session,
    preflight,
)
from odohil.session.signals import signal_of, signals_raise
from odohil.session.text.outcome import outcome_line
from odohil.session.text.run import MAY_STILL_MOVE, Said
from odohil.session.wizard.dialogue import WIZARD_PLAN, continue_with, guided_run, wizard_spec
from odohil.session.wizard.interrupts import Interrupts, wait_readable
from odohil.session.wizard.motion_steps import MotionSteps, pose_text
from odohil.session.wizard.validate import DETECT_HELP, GuidedValidation


class WizardScreen:
    """The wizard's console, the :class:`~odohil.session.wizard.dialogue.OperatorScreen`
    of the operator's dialogue: it renders lines, the motion bar and the live
    panel, and reads replies; what is said and asked when is
    odohil/session/wizard/dialogue.py's. The motion bar counts a motion's
    steps (legs and turns), each filled by how far its distance or angle has
    been covered (odohil/session/wizard/motion_steps.py), beside the live encoder pose."""

    def __init__(
        self, console: Console, system: units.UnitSystem = units.DEFAULT_UNIT_SYSTEM
    ) -> None:
        self.console = console
        self.system = system
        self._bar: tuple[Progress, TaskID, MotionSteps] | None = None

    def ask(self, prompt: Said) -> str:
        """Show ``prompt`` and read the line typed (once input is ready)."""
        self.console.print(said_text(prompt), end="")
        wait_readable(sys.stdin)
        return input()

    def say(self, *said: Said, wrap: bool = True) -> None:
        """Show lines, each head in its tone's colour."""
        print_said(self.console, *said, soft_wrap=not wrap)

    def motion(self, design: Drivable | None) -> None:
        """Show the motion bar of a new motion of ``design``; None closes it."""
        if self._bar is not None:
            self._bar[0].stop()
            self._bar = None
        if design is None:
            return
        steps = MotionSteps(design)
        progress = Progress(
            TextColumn("driving {task.description}"),
            BarColumn(),
            TextColumn("{task.percentage:>3.0f}%"),
            TimeElapsedColumn(),
            TextColumn("{task.fields[pose]}"),
            console=self.console,
            refresh_per_second=8,
        )
        task = progress.add_task(design.label(), total=len(steps.steps), pose="")
        progress.start()
        self._bar = (progress, task, steps)

    def motion_sample(self, sample: OdometrySample) -> None:
        """An encoder sample of the motion shown."""
        if self._bar is None:
            return
        progress, task, steps = self._bar
        if (done := steps.sample(sample)) is not None:
            progress.update(task, completed=done, pose=pose_text(sample))

    def estimate(
        self, trials: Sequence[CompletedTrial], result: EstimateResult, remaining: int
    ) -> None:
        """The live estimate panel after a solved trial."""
        self.console.print(estimate_panel(trials, result, remaining, self.system))


def wizard(
    port: PortOption = None,
    robot_file: Annotated[Path | None, robot_option(" For new sessions.")] = None,
    plan_text: Annotated[
        str | None,
        typer.Option("--plan", help=f'Designs and trial counts (default "{WIZARD_PLAN}").'),
    ] = None,
    session: Annotated[
        Path | None,
        typer.Option("--session", help="Session folder; an existing one is resumed."),
    ] = None,
    baud: BaudOption = None,
    max_leg_m: Annotated[
        float,
        option(
            "--max-leg-m",
            bound="max_leg_m",
            help="Longest leg the floor allows, m (the same option as plan's).",
        ),
    ] = DEFAULT_MAX_LEG_M,
    units_choice: UnitsOption = UNITS_DEFAULT,
    allow_turns: AllowTurnsOption = False,
    validate: Annotated[Path | None, typer.Option("--validate", help="Validate this calibrated "
                        "session on --path with the tape instead (journaled in "
                        "SESSION/validation/<path>/ or --session; exit 0 pass, 3 fail).")] = None,
    path_text: Annotated[str | None, option("--path", help=PATH_SYNTAX)] = None,
    trials: Annotated[int | None, option("--trials", bound="plan_n", help="Trials of --path "
                      "(a new validation).")] = None,
    detect: Annotated[str | None, option("--detect", help=DETECT_HELP)] = None,
) -> None:  # fmt: skip
    """Guide a calibration session beside the robot, one trial at a time
    (with --validate SESSION --path PATH: a validation of it)."""
    console = Console(highlight=False)
    interrupts = Interrupts.on_stderr(EXIT_INTERRUPTED, EXIT_STOP_UNCONFIRMED, MAY_STILL_MOVE)
    with interrupts.installed():  # Python's Ctrl-C back on the way out
        with bad_inputs():  # --validate, or a validation session continued by --session alone
            spec, guide = wizard_spec(
                session,
                robot_file,
                plan_text,
                port,
                baud,
                max_leg_m,
                allow_turns,
                validate,
                path_text,
                trials,
                detect,
            )
        if guide is not None:
            if not guide.trusted:
                print_refusal(console, guide.calibration.outcome, None, "nothing driven")
                raise typer.Exit(EXIT_UNTRUSTED)
            print_lines(console, [outcome_line(guide.calibration.outcome), *guide.sizing_lines()])
        console.print("[bold]Pre-flight checks[/] (nothing moves until all pass)")
        with signals_raise():
            code = _guided(console, spec, interrupts, unit_system(units_choice), guide)
        again = f"the wizard again with --session {spec.folder}" if guide is None else guide.again
        if code not in (EXIT_OK, EXIT_BAD_INPUT, EXIT_UNTRUSTED, EXIT_STOP_UNCONFIRMED):
            console.print(f"Stopped. The journal is in {spec.folder}; run {again} to continue.")
        raise typer.Exit(code)


def _guided(
    console: Console,
    spec: SessionSpec,
    interrupts: Interrupts,
    system: units.UnitSystem,
    guide: GuidedValidation | None,
) -> int:
    """Pre-flight (each check a tick), open the session (resume or start it:
    locked, connected), then run; a pre-flight failure exits by its class."""

    def tick(check: PreflightCheck) -> None:
        console.print(check_line(check))

    try:
        prepared = prepared_or_exit(preflight(spec), console, tick)
        with open_session(prepared, tick) as opened:
            if opened.torn is not None:
                console.print(f"[yellow]warning:[/] {opened.torn.describe()}")
            interrupts.robot = opened.robot
            return _run(console, opened, interrupts, system, guide)
    except PreflightFailed as exc:
        refuse(console, exc.check, tick)
    except KeyboardInterrupt as exc:
        return exit_for_signal(signal_of(exc))


def _run(
    console: Console,
    opened: Opened,
    interrupts: Interrupts,
    system: units.UnitSystem,
    guide: GuidedValidation | None,
) -> int:
    """The session with the operator's prompts and screens, to the final screen."""
    screen = WizardScreen(console, system)
    outcome = guided_run(opened, screen, interrupts, guide)
    if outcome.status == "finished" and guide is not None:
        passed, lines = guide.final(outcome.state)
        print_lines(console, lines)
        return EXIT_OK if passed else EXIT_UNTRUSTED
    if outcome.status == "finished":
        return final_screen(console, outcome.state)
    report_run(console, outcome, continue_with(opened, guide), interrupted="Interrupted")
    return exit_for_run(outcome)


def final_screen(console: Console, state: SessionState) -> int:
    """The wizard's last words: the session's verdict by the one recipe
    (odohil/session/results/outcome.py), why it may not be exported, and the exit status."""
    outcome = final_estimate(state)
    print_verdict(console, outcome)
    return exit_for_outcome(outcome)
