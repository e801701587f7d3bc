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

import math
import os
import re
import select
import signal
import sys
from dataclasses import dataclass
from pathlib import Path
from types import FrameType
from typing import Annotated, Any, TextIO

import numpy as np
import typer
from rich.console import Console
from rich.markup import escape

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
from odohil.cli.line import register_fake_urls
from odohil.cli.options import UNITS_DEFAULT, UnitsOption, bounded, unit_system
from odohil.cli.render import Check, MotionProgress, check_line, estimate_panel
from odohil.cli.robot_option import ROBOT_HELP, robot_callback
from odohil.cli.run import ALLOW_TURNS_HELP
from odohil.cli.session_view import (
    MAY_STILL_MOVE,
    BaudOption,
    default_session_folder,
    report_run,
)
from odohil.cli.verdict import export_refusal_lines, outcome_line
from odohil.driver.odometry import OdometrySample
from odohil.errors import MeasurementError, OdohilError
from odohil.science.estimators import EstimateResult
from odohil.science.floor_marks import marks_from_pose
from odohil.science.grouping import by_design
from odohil.science.moments import pose_moments
from odohil.science.parameters import NOMAD150, ErrorParameters
from odohil.science.paths import Design
from odohil.science.planner import DEFAULT_MAX_LEG_M
from odohil.science.robot_description import RobotDescription
from odohil.session import state as ev
from odohil.session.engine import (
    StartCheck,
)
from odohil.session.floor_space import check_floor
from odohil.session.journal import Record
from odohil.session.lifecycle import (
    Opened,
    PreflightCheck,
    PreflightFailed,
    SessionSpec,
    final_estimate,
    open_session,
    preflight,
    require,
    run_session,
)
from odohil.session.lifecycle.measure import OPERATOR
from odohil.session.plan import Plan
from odohil.session.preflight import (
    check_estimable,
)
from odohil.session.robot import Robot
from odohil.session.signals import signal_of, signals_raise
from odohil.session.sources import OperatorSource, TrialContext, check_distance
from odohil.session.start_pose import StartPose
from odohil.session.state import SessionState

SECOND_CTRL_C_STOP_S = 0.5
"""How long a second Ctrl-C waits for the robot to confirm its one ``st``, s."""
DEFAULT_PLAN = "k=1,l=6,n=30;k=20,l=0.5,n=30"
MAX_WIRE = 32767
"""Largest relative move one ``pr`` carries, 0.1 in."""
_SAMPLES = 400
_SPREAD_SIGMAS = 4.0
BACK_WORDS = ("back", "-")
"""What the operator types at a distance prompt to correct the value typed just before."""
_NUMBER = re.compile(r"^\s*(?P<number>[^a-z\s]*|nan|inf|[+-]inf|infinity)\s*(?P<unit>mm|cm|m)?\s*$")


# --- distances -------------------------------------------------------------


def parse_metres(text: str, label: str) -> float:
    """A typed distance in metres: ``0.012``, ``12 mm``, ``1.2cm``, ``0.012 m``.
    The one parse of what the operator typed: the number and its unit become
    metres here (:data:`odohil.units.METRES_PER_LENGTH_UNIT`), and from here on
    the distance stays that float, up to its journal record.

    Raises:
        MeasurementError: not a number (with an optional unit), or not a
            distance (:func:`~odohil.session.sources.check_distance`).
    """
    match = _NUMBER.match(text.strip().lower())
    if match is None or not match.group("number"):
        raise MeasurementError(
            f"{text.strip()!r} is not a number of metres (e.g. 0.012, 12 mm or 1.2 cm)"
        )
    try:
        number = float(match.group("number"))
    except ValueError:
        raise MeasurementError(
            f"{text.strip()!r} is not a number of metres (e.g. 0.012, 12 mm or 1.2 cm)"
        ) from None
    return check_distance(units.to_metres(number, match.group("unit") or "m"), label)


@dataclass(frozen=True)
class ExpectedRange:
    """What the model expects of one distance, metres.

    Attributes:
        low, high: the expected range (model spread, 4 sigma, plus tape error).
        limit: beyond this the value is physically implausible for the trial.
    """

    low: float
    high: float
    limit: float


def expected_ranges(
    description: RobotDescription,
    design: Design,
    params: tuple[ErrorParameters, ...],
    seed: int = 0,
) -> tuple[ExpectedRange, ...]:
    """Per distance, the range the model predicts under any of ``params``
    (Monte Carlo of the model's Gaussian pose change through the forward model)."""
    rng = np.random.default_rng(seed)
    lows: list[np.ndarray[Any, np.dtype[np.float64]]] = []
    highs: list[np.ndarray[Any, np.dtype[np.float64]]] = []
    for p in params:
        moments = pose_moments(design.path(), p)
        poses = rng.multivariate_normal(moments.mean, moments.cov, _SAMPLES, method="eigh")
        values = np.array([marks_from_pose(description, pose).as_array() for pose in poses])
        mean, sd = values.mean(axis=0), values.std(axis=0)
        lows.append(mean - _SPREAD_SIGMAS * sd)
        highs.append(mean + _SPREAD_SIGMAS * sd)
    tape = 3.0 * description.sigma_m
    low = np.clip(np.min(lows, axis=0) - tape, 0.0, None)
    high = np.max(highs, axis=0) + tape
    radius = float(np.max(np.hypot(description.positions()[:, 0], description.positions()[:, 1])))
    limit = design.distance_m + 2.0 * radius + 0.1
    return tuple(ExpectedRange(float(a), float(b), limit) for a, b in zip(low, high, strict=True))


# --- Ctrl-C ----------------------------------------------------------------


class Interrupts:
    """SIGINT policy: during a motion the first Ctrl-C is raised at the next
    encoder sample (the driver then stops the robot); elsewhere at once; a
    second Ctrl-C sends one ``st`` to :attr:`robot` (waiting at most
    :data:`SECOND_CTRL_C_STOP_S` for the confirmation) and exits the process
    at once: 130 if the robot confirmed, 4 if not."""

    def __init__(self) -> None:
        self.count = 0
        self.in_motion = False
        self.pending = False
        self.robot: Robot | None = None

    def install(self) -> None:
        """Take over SIGINT."""
        signal.signal(signal.SIGINT, self._handler)

    def _handler(self, signum: int, frame: FrameType | None) -> None:
        self.count += 1
        if self.count >= 2:
            os.write(2, b"\nsecond Ctrl-C: one st, then exiting at once\n")
            stopped = False
            if self.robot is not None:
                try:
                    self.robot.stop_and_confirm(SECOND_CTRL_C_STOP_S)
                    stopped = True
                except BaseException:
                    stopped = False
            if stopped:
                os.write(2, b"robot stopped (it reported standing still)\n")
                os._exit(EXIT_INTERRUPTED)
            os.write(2, f"WARNING: {MAY_STILL_MOVE}\n".encode())
            os._exit(EXIT_STOP_UNCONFIRMED)
        if self.in_motion:
            self.pending = True
            os.write(2, b"\nCtrl-C: stopping the robot...\n")
            return
        raise KeyboardInterrupt("Ctrl-C")

    def check(self) -> None:
        """Raise the Ctrl-C deferred during a motion."""
        if self.pending:
            self.pending = False
            raise KeyboardInterrupt("Ctrl-C")


def _wait_readable(stream: TextIO, slice_s: float = 0.1) -> None:
    """Wait until ``stream`` has a line, waking every ``slice_s`` seconds so that
    a signal the kernel handed to another thread (numpy's) is acted on at once:
    a read blocked in the main thread would not see it until the next key.
    Only on a terminal, which hands over one line per read (a pipe's lines may
    already sit in the stream's buffer)."""
    try:
        if not stream.isatty():
            return
        fd = stream.fileno()
    except (AttributeError, OSError, ValueError):
        return
    while not select.select([fd], [], [], slice_s)[0]:
        pass


# --- the operator's side ---------------------------------------------------


class WizardPrompts:
    """The :class:`~odohil.session.sources.OperatorPrompts` of the wizard."""

    def __init__(
        self,
        console: Console,
        description: RobotDescription,
        interrupts: Interrupts,
        progress: MotionProgress,
    ) -> None:
        self.console = console
        self.description = description
        self.interrupts = interrupts
        self.progress = progress
        self.estimate: ErrorParameters | None = None
        self._ranges: dict[tuple[int, int, int], tuple[ExpectedRange, ...]] = {}
        self._shown: set[tuple[int, int]] = set()
        self._helped: set[tuple[int, int]] = set()
        # per (trial, attempt, rejections): a typed value held until the next is
        # typed (so ``back`` can correct it), and values a rejection did not name
        self._held: dict[tuple[int, int, int], dict[int, float]] = {}
        self._kept: dict[tuple[int, int, int], dict[int, float]] = {}

    def _input(self, prompt: str) -> str:
        try:
            self.console.print(prompt, end="")
            _wait_readable(sys.stdin)
            return input()
        except EOFError:
            raise MeasurementError("the input ended (no operator at the terminal)") from None

    def _header(self, ctx: TrialContext, resumed: bool) -> None:
        """The trial's context, once per attempt: number, design, driving; on a
        resumed attempt also where it stands and what was already entered."""
        self._shown.add((ctx.trial, ctx.attempt))
        self.console.print(
            f"\n[bold]Trial {ctx.trial}/{ctx.n_trials}[/] (attempt {ctx.attempt}): "
            f"{ctx.design.label()}, {ctx.design.distance_m:g} m of driving"
            + (
                " [bold](resumed: the motion is done, its marks are on the floor)[/]"
                if resumed
                else ""
            )
            + "."
        )
        if resumed and ctx.measurements:
            entered = ", ".join(
                f"{label} = {value:.4f} m"
                for label, value in zip(ctx.labels, ctx.measurements, strict=False)
            )
            left = len(ctx.labels) - len(ctx.measurements)
            self.console.print(
                f"Already entered and saved: {entered}; {units.plural(left, 'distance')} to go."
            )

    def _context(self, ctx: TrialContext) -> None:
        """Show the trial's context if this wizard has not shown it yet (a resume)."""
        if (ctx.trial, ctx.attempt) not in self._shown:
            self._header(ctx, resumed=True)

    def confirm_start_marks(self, ctx: TrialContext) -> None:
        """Ask for the start marks."""
        screws = ", ".join(self.description.screw_names)
        self._header(ctx, resumed=False)
        self._input(
            f"Mark the floor at the {len(self.description.screws)} screws ({screws}), "
            "keep clear of the robot, then press Enter to start the motion: "
        )

    def confirm_end_marks(self, ctx: TrialContext) -> None:
        """The motion is over: ask for the end marks."""
        self.progress.stop()
        self.interrupts.in_motion = False
        self.interrupts.check()
        self._context(ctx)
        pose = ctx.encoder_end_pose
        if pose is not None:
            self.console.print(
                f"Motion done; encoders say x={pose[0]:+.4f} m y={pose[1]:+.4f} m "
                f"heading {math.degrees(pose[2]):+.2f} deg from the start."
            )
        self._input("Mark the floor at the screws again (end marks), then press Enter: ")

    def _range(self, ctx: TrialContext, index: int) -> ExpectedRange:
        key = (ctx.trial, ctx.attempt, 0 if self.estimate is None else 1)
        if key not in self._ranges:
            params = (NOMAD150,) if self.estimate is None else (NOMAD150, self.estimate)
            self._ranges[key] = expected_ranges(self.description, ctx.design, params, ctx.trial)
        return self._ranges[key][index]

    def ask_distance(self, ctx: TrialContext, index: int) -> float:
        """Distance ``index`` in metres. A distance a rejection did not name is
        kept without asking. Otherwise the value is handed over only once the
        next distance is typed, so that typing ``back`` (or ``-``) at the next
        prompt corrects it; the next value is then held for the next call."""
        self._context(ctx)
        key = (ctx.trial, ctx.attempt, ctx.rejections)
        kept = self._kept.get(key, {})
        label = ctx.labels[index]
        if index in kept:
            self.console.print(f"{label}: {kept[index]:.4f} m kept (the rejection did not name it)")
            return kept[index]
        held = self._held.setdefault(key, {})
        value = held.pop(index) if index in held else self._read_first(ctx, index)
        following = [j for j in range(index + 1, len(ctx.labels)) if j not in kept]
        while following:
            answer = self._read_distance(ctx, following[0], index)
            if answer is not None:
                held[following[0]] = answer
                break
            self.console.print(f"Correct {label}:")
            value = self._read_first(ctx, index)
        return value

    def _read_first(self, ctx: TrialContext, index: int) -> float:
        """Distance ``index`` with nothing before it to go back to."""
        value = self._read_distance(ctx, index, None)
        assert value is not None  # back is refused when there is nothing to go back to
        return value

    def _read_distance(self, ctx: TrialContext, index: int, back_to: int | None) -> float | None:
        """Ask until the answer is a plausible distance; return it in metres, or
        None when the operator typed ``back`` to correct distance ``back_to``."""
        label = ctx.labels[index]
        expected = self._range(ctx, index)
        hint = f"expected {expected.low:.4f} to {expected.high:.4f} m"
        back = f"; back: correct {ctx.labels[back_to]}" if back_to is not None else ""
        if (ctx.trial, ctx.attempt) not in self._helped:
            self._helped.add((ctx.trial, ctx.attempt))
            self.console.print(
                "Type each distance in metres, or with a unit (12 mm, 1.2 cm); "
                f"type {' or '.join(BACK_WORDS)} to correct the value typed just before."
            )
        unconfirmed: float | None = None
        while True:
            text = self._input(
                f"Trial {ctx.trial}/{ctx.n_trials}, {label}, metres ({hint}{back}): "
            )
            if text.strip().lower() in BACK_WORDS:
                if back_to is not None:
                    return None
                self.console.print(
                    "[yellow]nothing to go back to:[/] only the value typed just before can be "
                    "corrected, and the earlier ones are saved; type this distance"
                )
                continue
            try:
                value = parse_metres(text, label)
            except MeasurementError as exc:
                self.console.print(f"[red]refused:[/] {exc}; type it again")
                continue
            if value > expected.limit:
                self.console.print(
                    f"[red]refused:[/] {value:g} m is implausible: the marks of this trial "
                    f"cannot be more than {expected.limit:.2f} m apart; type it again"
                )
                continue
            if not expected.low <= value <= expected.high and value != unconfirmed:
                self.console.print(
                    f"[yellow]check:[/] {value:g} m is outside the expected range ({hint}); "
                    "type the same value again to keep it, or the corrected one"
                )
                unconfirmed = value
                continue
            return value

    def ask_remeasure(self, ctx: TrialContext, index: int, reason: str) -> float | None:
        """The slip check doubts the trial: ask for the suspect distance again."""
        self._context(ctx)
        label = ctx.labels[index]
        previous = ctx.measurements[index] if index < len(ctx.measurements) else float("nan")
        self.console.print(f"[yellow]check the marks:[/] {reason}")
        while True:
            text = self._input(
                f"Re-measure {label}, metres (you typed {previous:.4f}; press Enter to keep it): "
            )
            if not text.strip():
                return None
            try:
                return parse_metres(text, label)
            except MeasurementError as exc:
                self.console.print(f"[red]refused:[/] {exc}; type it again")

    def ask_extra_distance(self, ctx: TrialContext, label: str, reason: str) -> float | None:
        """The trial is ambiguous: ask for one more cross distance, named by its screws."""
        self._context(ctx)
        self.console.print(f"[yellow]two poses fit these marks:[/] {reason}")
        while True:
            text = self._input(
                f"Measure one more distance, {label}, metres (press Enter if you cannot; "
                "the trial is then left out): "
            )
            if not text.strip():
                return None
            try:
                return parse_metres(text, label)
            except MeasurementError as exc:
                self.console.print(f"[red]refused:[/] {exc}; type it again")

    def start_check(self, robot: Robot) -> StartCheck:
        """Before the session goes on: show where the robot stands; if it is not
        at the next trial's start, ask the operator to put it back there, then
        set the encoders to that start pose."""

        def check(start: StartPose) -> None:
            self.console.print(f"Robot: {start.describe()}")
            if start.ok or start.expected is None:
                return
            answer = self._input(
                f"[bold]Put the robot back where trial {start.trial} starts[/] (the end marks "
                "of the last trial, or this trial's start marks), then press Enter; or type "
                "'here' to start the trial where it stands: "
            )
            if answer.strip().lower() == "here":
                self.console.print("The trial starts where the robot stands.")
                return
            robot.zero(start.expected)
            self.console.print("Encoders set to the trial's start.")

        return check

    def show_rejection(self, ctx: TrialContext, reason: str) -> None:
        """The set of distances fits no rigid motion: say why; only the
        distances the rejection names are asked for again, the others are kept."""
        named = [i for i, label in enumerate(ctx.labels) if label in reason]
        if named and len(named) < len(ctx.measurements):
            self._kept[(ctx.trial, ctx.attempt, ctx.rejections + 1)] = {
                i: value for i, value in enumerate(ctx.measurements) if i not in named
            }
            again = ", ".join(ctx.labels[i] for i in named)
            what = f"only {again} (the other distances are kept)"
        else:
            what = "all of this trial's distances"
        self.console.print(
            f"[red]These distances fit no rigid motion:[/] {reason}\nMeasure again {what}."
        )


class WizardObserver:
    """Sees the session unfold: trial headers, motion bar, solved pose, live table."""

    def __init__(
        self,
        console: Console,
        prompts: WizardPrompts,
        interrupts: Interrupts,
        progress: MotionProgress,
        system: units.UnitSystem = units.DEFAULT_UNIT_SYSTEM,
    ) -> None:
        self.console = console
        self.system = system
        self.prompts = prompts
        self.interrupts = interrupts
        self.progress = progress
        self._step = 0
        self._step_start: OdometrySample | None = None

    def on_sample(self, sample: OdometrySample) -> None:
        """Every odometry sample of a motion: the first is taken before the
        first step; a step ends at the first sample that shows the robot at rest."""
        if self._step_start is None:
            self._step_start = sample
        else:
            self.progress.update(self._step, self._step_start, sample)
            if not sample.moving:
                self._step += 1
                self._step_start = sample
        self.interrupts.check()

    def record(self, record: Record, state: SessionState) -> None:
        """React to one journaled record."""
        kind, data = record.kind, record.data
        if kind == ev.MOTION_START:
            opened = state.open_trial
            assert opened is not None
            assert state.plan is not None
            self._step, self._step_start = 0, None
            self.interrupts.in_motion = True
            self.progress.start(state.plan.design_of(opened.trial))
        elif kind == ev.SOLVED:
            trial = state.completed[-1]
            x, y, theta = trial.pose_change
            self.console.print(
                f"[green]Trial {trial.trial} solved:[/] dx={1e3 * x:+.1f} mm "
                f"dy={1e3 * y:+.1f} mm dtheta={math.degrees(theta):+.3f} deg"
                + ("" if trial.clear_cut else f" [yellow](not clear-cut: {trial.note})")
            )
            if not _can_estimate(state):
                self.console.print("No estimate yet: it needs 2 trials of a design.")
        elif kind == ev.VOID:
            self.progress.stop()
            self.console.print(f"[yellow]Trial {data['trial']} attempt voided:[/] {data['reason']}")
        elif kind == ev.FINISHED:
            self.console.print(
                f"[bold green]Session complete:[/] {units.plural(data['n_trials'], 'trial')}."
            )

    def estimated(self, result: EstimateResult, state: SessionState) -> None:
        """The live estimate: the expected distances follow it; show the table."""
        self.prompts.estimate = result.params
        assert state.plan is not None
        remaining = state.plan.n_trials - len(state.completed)
        self.console.print(estimate_panel(state.completed, result, remaining, self.system))


def _can_estimate(state: SessionState) -> bool:
    designs = by_design(state.completed, lambda trial: trial.design.forward)
    return any(
        len(trials) >= 2 and design.path().signed_distance_m != 0
        for design, trials in designs.items()
    )


# --- pre-flight --------------------------------------------------------------


def plan_checks(plan: Plan, max_leg_m: float) -> list[Check]:
    """Is every design of the plan something the robot can drive?"""
    problems = []
    for item in plan.items:
        leg = item.design.l_m
        if leg > max_leg_m:
            problems.append(f"{item.design.label()}: legs of {leg:g} m exceed {max_leg_m:g} m")
        if abs(units.metres_to_wire(leg)) > MAX_WIRE:
            problems.append(f"{item.design.label()}: a leg does not fit one move command")
    detail = (
        f"{units.plural(plan.n_trials, 'trial')}, {plan.distance_m:.1f} m of driving "
        f"({plan.to_text()})"
        if not problems
        else "; ".join(problems)
    )
    return [Check("plan feasible", not problems, detail)]


def estimable_check(plan: Plan, description: RobotDescription) -> Check:
    """Can trials of this plan, all driven, give an estimate of the four
    parameters (:func:`odohil.session.preflight.check_estimable`)?"""
    try:
        check_estimable(plan, description)
    except OdohilError as exc:
        return Check("plan estimable", False, str(exc))
    return Check("plan estimable", True, "its trials can identify the four parameters")


def floor_check(plan: Plan, description: RobotDescription) -> Check:
    """Does the plan fit the robot description's free floor ([floor] length_m)?"""
    try:
        check_floor(plan, description)
    except OdohilError as exc:
        return Check("floor space", False, str(exc))
    given = description.floor_length_m
    limit = f"of {given:g} m" if given is not None else "(no [floor] length_m given)"
    return Check("floor space", True, f"the plan needs {plan.excursion_m:g} m of floor {limit}")


def wizard(
    port: Annotated[
        str | None,
        typer.Option(
            "--port",
            help="Serial port (or pyserial URL) of the robot "
            "(default: the session's, else robot.toml \\[serial] port).",
        ),
    ] = None,
    robot_file: Annotated[
        Path | None,
        typer.Option("--robot", callback=robot_callback, help=ROBOT_HELP + " For new sessions."),
    ] = None,
    plan_text: Annotated[
        str | None,
        typer.Option("--plan", help=f'Designs and trial counts (default "{DEFAULT_PLAN}").'),
    ] = None,
    session: Annotated[
        Path | None,
        typer.Option("--session", help="Session folder; an existing one is resumed."),
    ] = None,
    baud: BaudOption = None,
    max_leg_m: Annotated[
        float,
        typer.Option(
            "--max-leg-m",
            callback=bounded("max_leg_m"),
            help="Longest leg the floor allows, m (the same option as plan's).",
        ),
    ] = DEFAULT_MAX_LEG_M,
    units_choice: UnitsOption = UNITS_DEFAULT,
    allow_turns: Annotated[bool, typer.Option("--allow-turns", help=ALLOW_TURNS_HELP)] = False,
) -> None:
    """Guide a calibration session beside the robot, one trial at a time."""
    console = Console(highlight=False)
    interrupts = Interrupts()
    interrupts.install()
    folder = session or default_session_folder()
    spec = SessionSpec(
        folder, "auto", robot_file, plan=plan_text, default_plan=DEFAULT_PLAN,
        measure=OPERATOR, port=port, baud=baud, max_leg_m=max_leg_m, allow_turns=allow_turns,
        allow_few_trials=True, note={"by": "wizard", "port": port},
    )  # fmt: skip
    console.print("[bold]Pre-flight checks[/] (nothing moves until all pass)")
    with signals_raise():
        code = _guided(console, spec, interrupts, unit_system(units_choice))
    if code not in (EXIT_OK, EXIT_BAD_INPUT, EXIT_UNTRUSTED, EXIT_STOP_UNCONFIRMED):
        console.print(
            f"Stopped. The journal is in {folder}; run the wizard again with "
            f"--session {folder} to continue."
        )
    raise typer.Exit(code)


def _tick(console: Console, check: PreflightCheck) -> None:
    console.print(check_line(Check(check.name, check.passed, check.message)))


def _guided(
    console: Console, spec: SessionSpec, interrupts: Interrupts, system: units.UnitSystem
) -> int:
    """Pre-flight (each check a tick), open the session (resume or start it:
    locked, connected), then run; any pre-flight failure exits 2."""
    checked = preflight(spec)
    for check in checked.checks:
        _tick(console, check)
    try:
        prepared = require(checked)
        for warning in prepared.warnings:
            console.print(f"[yellow]warning:[/] {escape(warning)}", soft_wrap=True)
        register_fake_urls(prepared.line.port)
        with open_session(prepared, lambda check: _tick(console, check)) as opened:
            if opened.torn is not None:
                console.print(f"[yellow]warning:[/] {opened.torn.describe()}")
            interrupts.robot = opened.robot
            return _run(console, opened, interrupts, system)
    except PreflightFailed as exc:
        if exc.check not in checked.checks:
            _tick(console, exc.check)
        console.print("[red]Pre-flight failed: nothing was moved.[/]")
        return EXIT_BAD_INPUT
    except KeyboardInterrupt as exc:
        return exit_for_signal(signal_of(exc))


def _run(console: Console, opened: Opened, interrupts: Interrupts, system: units.UnitSystem) -> int:
    """The session with the operator's prompts and screens, to the final screen."""
    progress = MotionProgress(console)
    prompts = WizardPrompts(console, opened.prepared.description, interrupts, progress)
    observer = WizardObserver(console, prompts, interrupts, progress, system)
    try:
        outcome = run_session(
            opened, observer, source=OperatorSource(prompts), on_sample=observer.on_sample,
            start_check=prompts.start_check(opened.robot),
        )  # fmt: skip
    finally:
        progress.stop()
    if outcome.status == "finished":
        return final_screen(console, outcome.state)
    report_run(console, outcome, _again(opened), interrupted="Interrupted")
    return exit_for_run(outcome)


def _again(opened: Opened) -> str:
    """The command that continues a wizard session (``odohil resume`` refuses them)."""
    return f"odohil wizard --session {opened.journal.folder}"


def final_screen(console: Console, state: SessionState) -> int:
    """The wizard's last words: the session's verdict by the one recipe
    (odohil/session/outcome.py), why it may not be exported, and the exit status."""
    outcome = final_estimate(state)
    console.print(outcome_line(outcome), soft_wrap=True, markup=False)
    for line in export_refusal_lines(outcome):
        console.print(line, soft_wrap=True, markup=False)
    return exit_for_outcome(outcome)


def register(app: typer.Typer) -> None:
    """Add ``wizard`` to the ``odohil`` app."""
    app.command("wizard")(wizard)
