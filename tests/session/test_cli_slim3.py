"""What the CLI used to decide itself and now asks the session layer for
(issue 18, third round; tests/session/test_cli_slim2.py for the second), in
process: the wizard's dialogue with the operator (odohil/session/wizard/dialogue.py)
on a scripted screen: the trial's header once per attempt, a refused reply
and the instructions, which distances a rejection asks for again, the slip
check's question, the put-back of the start check; and what the operator sees
of the session unfolding."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
import pytest

import fakes
from odohil import units
from odohil.driver.odometry import OdometrySample
from odohil.errors import InconsistentMeasurementError, MeasurementError, ParameterError
from odohil.robots import __file__ as robots_init
from odohil.science.closed_forms import forth_and_back_means
from odohil.science.estimators import EstimateResult
from odohil.science.floor_marks import distance_labels
from odohil.science.parameters import NOMAD150
from odohil.science.paths import Design, Drivable
from odohil.science.simulator import simulate
from odohil.session.commands.demo import demo_session
from odohil.session.commands.design import (
    named_path,
    path_moments,
    predict_rows,
    write_simulated_trials,
)
from odohil.session.commands.design_tables import covariance_table, predict_table
from odohil.session.commands.import_log import import_recording
from odohil.session.commands.plan import PlannedExperiment, PlanRequest
from odohil.session.commands.plan_paths import ScoredPaths, plan_outcome
from odohil.session.commands.validate import (
    chi_square_table,
    held_out,
    validation_setup,
    verdict_lines,
)
from odohil.session.journal.events import OPERATOR, Event, Void, encode
from odohil.session.journal.file import Record
from odohil.session.journal.state import CompletedTrial, SessionState
from odohil.session.measure.tape.records import (
    MeasurementsRejected,
    Remeasured,
    TapeContext,
    TapeReadings,
)
from odohil.session.plans.plan import parse_plan
from odohil.session.results.outcome import estimate_source
from odohil.session.results.validation import ValidationTrials, check_trials, trials_of_session
from odohil.session.robots.registry import emulate_help, emulated_backends
from odohil.session.run import SessionSpec, open_session, preflight, require, run_session
from odohil.session.run.start_pose import HERE, StartPose
from odohil.session.text.operator import measured_again, remeasured
from odohil.session.text.outcome import (
    number_text,
    parameter_rows,
    parameters_line,
    parameters_text,
)
from odohil.session.text.run import RunWatch, Said
from odohil.session.trials.logs import ImportOptions
from odohil.session.trials.logs.csv_log import write_csv_log
from odohil.session.trials.logs.recording import Recording
from odohil.session.trials.path_trial_file import read_path_trials
from odohil.session.wizard.dialogue import (
    WIZARD_PLAN,
    OperatorDialogue,
    OperatorWatch,
    wizard_spec,
)
from odohil.session.wizard.interrupts import Interrupts
from odohil.session.wizard.observables import OBSERVABLE_COLUMNS, observables_rows
from odohil.session.wizard.tape_entry import INSTRUCTIONS
from tests.logs.synth import synth_log, varied_motions
from tests.session.helpers import description

ROBOT = Path(robots_init).parent / "nomad150.toml"
PORT = "fakerobot://?seed=2&time_scale=2000"
DESIGN = parse_plan("k=1,l=1,n=2", "reverse").items[0].design
LABELS = distance_labels(description())


@dataclass
class Screen:
    """An :class:`~odohil.session.wizard.dialogue.OperatorScreen` that answers
    from ``replies`` and keeps what was said (EOFError when no reply is left)."""

    replies: list[str]
    said: list[Said] = field(default_factory=list)
    asked: list[Said] = field(default_factory=list)
    motions: list[Drivable | None] = field(default_factory=list)

    def ask(self, prompt: Said) -> str:
        self.asked.append(prompt)
        if not self.replies:
            raise EOFError
        return self.replies.pop(0)

    def say(self, *said: Said, wrap: bool = True) -> None:
        self.said.extend(said)

    def motion(self, design: Drivable | None) -> None:
        self.motions.append(design)

    def motion_sample(self, sample: OdometrySample) -> None:
        """Not used here."""

    def estimate(
        self, trials: Sequence[CompletedTrial], result: EstimateResult, remaining: int
    ) -> None:
        """Not used here."""


def _ctx(**changes: object) -> TapeContext:
    ctx = TapeContext(1, 1, 2, DESIGN, encoder_end_pose=(0.0, 0.0, 0.0), labels=LABELS)
    return replace(ctx, **changes)  # type: ignore[arg-type]


def _dialogue(*replies: str) -> tuple[OperatorDialogue, Screen]:
    screen = Screen(list(replies))
    interrupts = Interrupts(print, 130, 4, "the robot may still be moving")
    return OperatorDialogue(screen, description(), interrupts), screen


def test_a_distance_refused_then_checked_then_kept_after_the_header_and_instructions() -> None:
    dialogue, screen = _dialogue("abc", "0.5", "0.5", "0.05")
    assert dialogue.ask_distance(_ctx(), 0) == pytest.approx(0.5)  # held until d2 is typed
    header, instructions, refused, check = screen.said
    assert header.tone == "title"
    assert header.head.startswith("\nTrial 1/2 (attempt 1): ")
    assert instructions == Said("plain", INSTRUCTIONS)
    assert (refused.tone, refused.head) == ("error", "refused:")
    not_metres = "'abc' is not a number of metres (e.g. 0.012, 12 mm or 1.2 cm)"
    assert refused.text == f" {not_metres}; type it again"
    assert (check.tone, check.head) == ("note", "check:")
    assert "outside the expected range" in check.text
    assert screen.asked[0].head.startswith(f"Trial 1/2, {LABELS[0]}, metres (expected ")
    assert screen.asked[-1].head.startswith(f"Trial 1/2, {LABELS[1]}, metres (expected ")
    assert len(screen.asked) == 4


def test_a_rejection_asks_again_only_for_what_it_names() -> None:
    dialogue, screen = _dialogue()
    ctx = _ctx(readings=TapeReadings(measurements=(0.1, 0.2, 0.3, 0.4, 0.5)))
    dialogue.show_rejection(ctx, InconsistentMeasurementError("d2 is off", (LABELS[1],)))
    (said,) = screen.said  # no header: the attempt's distances were asked before
    assert (said.tone, said.head) == ("error", "These distances fit no rigid motion:")
    kept = "(the other distances are kept)."
    assert said.text == f" d2 is off\nMeasure again only {LABELS[1]} {kept}"
    everything = InconsistentMeasurementError("off", ())
    dialogue.show_rejection(ctx, everything)
    assert screen.said[-1].text.endswith("Measure again all its distances.")


def test_the_slip_checks_question_keeps_the_value_on_enter_and_refuses_words() -> None:
    dialogue, screen = _dialogue("twelve", "")
    ctx = _ctx(readings=TapeReadings(measurements=(0.1, 0.2, 0.3, 0.4, 0.5)))
    assert dialogue.ask_remeasure(ctx, 1, "d2 looks like a slip") is None
    header, entered, doubt, refused = screen.said
    assert "(resumed: the motion is done" in header.head
    assert entered.head.startswith(f"Already entered and saved: {LABELS[0]} = 0.1000 m")
    assert doubt == Said("note", "check the marks:", " d2 looks like a slip")
    assert (refused.head, refused.text.endswith("; type it again")) == ("refused:", True)
    assert screen.asked[0].head.startswith(f"Re-measure {LABELS[1]}, metres (you typed 0.2000")


def test_the_end_of_input_is_a_measurement_error() -> None:
    dialogue, _ = _dialogue()
    with pytest.raises(MeasurementError, match="the input ended"):
        dialogue.confirm_start_marks(_ctx())


def test_the_end_marks_close_the_motion_bar_and_show_the_encoders() -> None:
    dialogue, screen = _dialogue("")
    dialogue.interrupts.in_motion = True
    dialogue.confirm_end_marks(_ctx(encoder_end_pose=(1.0, 0.0, 0.0)))
    assert screen.motions == [None]
    assert not dialogue.interrupts.in_motion
    assert screen.said[-1].head.startswith("Motion done; encoders say x=+1.0000 m")


class _Robot:
    """Records where its encoders were zeroed (the start check's put-back)."""

    def __init__(self) -> None:
        self.zeroed: list[tuple[float, float, float]] = []

    def zero(self, pose: tuple[float, float, float]) -> None:
        self.zeroed.append(pose)


@pytest.mark.parametrize(("reply", "zeroed"), [("", True), (HERE, False)])
def test_a_robot_off_its_start_is_put_back_or_starts_here(reply: str, zeroed: bool) -> None:
    dialogue, screen = _dialogue(reply)
    robot = _Robot()
    start = StartPose(2, (0.5, 0.0, 0.0), (0.0, 0.0, 0.0))
    dialogue.start_check(robot)(start)  # type: ignore[arg-type]
    assert screen.asked[0].tone == "title"
    assert robot.zeroed == ([(0.5, 0.0, 0.0)] if zeroed else [])  # the trial's start


def test_a_voided_attempt_closes_the_bar_and_says_why() -> None:
    screen = Screen([])
    watch = OperatorWatch(screen, Interrupts(print, 130, 4, "may still be moving"))
    kind, data = encode(Void(trial=3, attempt=1, reason="the robot did not answer"))
    record = Record(1, kind, 0.0, data)
    watch.record(record, None)  # type: ignore[arg-type]
    assert screen.motions == [None]
    assert screen.said == [Said("note", "Trial 3 attempt voided:", " the robot did not answer")]


def _trial_file(folder: Path, design: Design, n: int, seed: int) -> Path:
    trials = folder / f"trials-{seed}.csv"
    poses = simulate(design.path(), NOMAD150, n, seed=seed, segment_m=0.01).pose_change
    write_simulated_trials(trials, design, poses)
    return trials


FILE = {"trials": 4, "measure": None, "port": None, "out": None}
"""held_out's options for trials read from a file."""


def _anywhere(start: StartPose) -> None:
    """Start every trial where the robot stands."""


def test_the_rows_of_the_parameters_table(tmp_path: Path) -> None:
    """odohil/session/text/outcome.py ``parameter_rows`` (a truth column: yes or NO)."""
    result = estimate_source([_trial_file(tmp_path, Design(1, 2.0), 12, 2)]).result
    assert result is not None
    truth = {p.name: p.value for p in result.parameters} | {"K_rho": 1.0}
    rows = {row[0]: row for row in parameter_rows(result, "si", truth)}
    assert list(rows) == ["E_R", "E_T", "K_theta", "K_rho"]
    assert rows["E_R"][1:] == [
        number_text("E_R", result.parameter("E_R").value, "si"),
        number_text("E_R", result.parameter("E_R").stderr, "si", digits=2),
        rows["E_R"][3],
        "rad/m",
        number_text("E_R", result.parameter("E_R").value, "si"),
        "yes",
    ]
    assert rows["K_rho"][-1] == "NO"
    assert all(len(row) == 5 for row in parameter_rows(result, "paper"))


def test_a_file_validation_is_set_up_read_and_told(tmp_path: Path) -> None:
    """odohil/session/commands/validate.py: ``validation_setup`` (a bad --alpha
    refused before anything is read), ``held_out`` of a file (nothing driven),
    the verdict lines and the tests' rows."""
    calibration = _trial_file(tmp_path, Design(1, 2.0), 12, 2)
    held = _trial_file(tmp_path, Design(0.5, 2.0), 6, 3)
    with pytest.raises(ParameterError, match="--alpha"):
        validation_setup(calibration, f"file:{held}", ROBOT, frozenset(), ImportOptions(), 0.9)
    setup = validation_setup(calibration, f"file:{held}", ROBOT, frozenset(), ImportOptions(), 0.05)
    assert setup.calibration.outcome.result is not None
    assert setup.robot.path == str(ROBOT)

    def no_drive(spec: SessionSpec) -> ValidationTrials:
        raise AssertionError("a file is not driven")

    found = held_out(setup, calibration, ImportOptions(), no_drive, **FILE)  # type: ignore[arg-type]
    assert (len(found.measured), found.folder, found.reread) == (4, None, False)
    with pytest.raises(ParameterError, match="--port and --measure are not used"):
        held_out(
            setup,
            calibration,
            ImportOptions(),
            no_drive,
            trials=4,
            measure="fake",
            port=None,
            out=None,
        )
    tested = check_trials(found.measured, setup.calibration.outcome.result, 0.05)
    lines = verdict_lines(tested, "file:held.csv")
    status = "PASS" if tested.passed else "FAIL"
    assert lines[0].startswith(f"validation: {status} (4 trials of file:held.csv")
    assert len(lines) == 1 + len(tested.reasons())
    shown = chi_square_table(tested)
    title, rows = shown.title, shown.rows
    assert title.endswith(f"each at level {tested.level:g}")
    assert [row[0] for row in rows] == [t.name for t in tested.tests]
    assert {row[-1] for row in rows} <= {"pass", "FAIL"}
    assert all(len(row) == len(shown.columns) for row in rows)
    assert (shown.words, shown.flagged) == (("test", "result"), ("FAIL",))


def test_a_driven_validation_is_driven_once_then_tested_again(tmp_path: Path) -> None:
    """``held_out`` of a driven path: the spec handed to the caller's drive,
    then, the validation finished, its trials tested again without driving;
    and the observables table of the calibration's trials."""
    fakes.register_url_handlers()
    calibration = tmp_path / "calibration"
    spec = SessionSpec(
        calibration,
        "new",
        ROBOT,
        plan="k=1,l=0.5,n=3;k=0.5,l=0.5,n=3",
        measure="fake",
        port=PORT,
        allow_few_trials=True,
    )
    with open_session(require(preflight(spec))) as opened:
        ran = run_session(opened, start_check=_anywhere)
    assert ran.status == "finished"
    shown = observables_rows(ran.state.completed)  # wizard/observables.py: the wizard's table
    assert shown[0][:2] == ("k=1 l=0.5 m turn", "3")
    assert all(shown[0])
    assert len(shown[0]) == len(OBSERVABLE_COLUMNS)
    assert observables_rows(ran.state.completed[:1]) == [
        ("k=1 l=0.5 m turn", "1", "needs 2 trials", "", "", "", "")
    ]
    setup = validation_setup(
        calibration, "forth-back:1,1", None, frozenset(), ImportOptions(), 0.05
    )
    driven: list[SessionSpec] = []

    def drive(spec: SessionSpec) -> ValidationTrials:
        driven.append(spec)
        with open_session(require(preflight(replace(spec, port=PORT, seed=1)))) as opened:
            outcome = run_session(opened, start_check=_anywhere)
        return trials_of_session(outcome.state, source=str(spec.folder))

    options = {"trials": 2, "measure": "fake", "port": PORT, "out": None}
    first = held_out(setup, calibration, ImportOptions(), drive, **options)  # type: ignore[arg-type]
    assert (len(first.measured), first.reread) == (2, False)
    assert first.folder == calibration / "validation" / driven[0].folder.name
    assert driven[0].purpose == "validate"
    again = held_out(setup, calibration, ImportOptions(), drive, **options)  # type: ignore[arg-type]
    assert (len(again.measured), again.folder, again.reread) == (2, first.folder, True)
    assert len(driven) == 1


@dataclass
class View:
    """A :class:`~odohil.session.text.run.RunView` that keeps what it was shown."""

    shown: list[object] = field(default_factory=list)

    def advance(self, completed: int) -> None:
        self.shown.append(("advance", completed))

    def describe(self, text: str) -> None:
        self.shown.append(("describe", text))

    def status(self, text: str) -> None:
        self.shown.append(("status", text))

    def say(self, *said: Said) -> None:
        self.shown.extend(said)


def _record(event: Event) -> Record:
    kind, data = encode(event)
    return Record(1, kind, 0.0, data)


def test_what_a_run_shows_as_it_runs() -> None:
    """odohil/session/text/run.py ``RunWatch``: the progress at each solved
    trial, a voided attempt, distances taken again after a rejection, and the
    slip check's summary of the trials whose doubted distance was taken again."""
    view = View()
    watch = RunWatch(view)
    state = SessionState(header={})
    watch.record(_record(Void(trial=2, attempt=1, reason="no answer")), state)
    watch.record(_record(MeasurementsRejected(trial=3, attempt=1, reason="x")), state)
    for trial, kept in ((5, False), (4, True), (5, False), (1, False)):
        remeasure = Remeasured(trial=trial, attempt=1, index=0, reason="slip", kept=kept)
        watch.record(_record(remeasure), state)
    watch.show_start(StartPose(1, None, (0.0, 0.0, 0.0)))
    assert view.shown == [
        ("status", "trial 2 attempt 1 void: no answer"),
        Said("plain", measured_again(3, "the simulated operator")),
        ("status", f"robot: {StartPose(1, None, (0.0, 0.0, 0.0)).describe()}"),
    ]
    assert watch.summary() == [Said("plain", remeasured([5, 1], "the simulated operator"))]
    assert RunWatch(View()).summary() == []


def test_emulate_help_names_each_fake_and_its_own_defaults() -> None:
    """odohil/session/robots/registry.py ``emulate_help``: from the backends' facts."""
    shown = emulate_help()
    for facts in emulated_backends():
        assert f"{facts.name} (the {facts.label})" in shown.robot
        assert f"{facts.name} {facts.default_baud:g}" in shown.baud
        assert f"{facts.name} " in shown.time_scale
    assert shown.robot.endswith("\\[robot] protocol is one of them.")


def test_a_plan_of_turn_designs_on_turns_with_error_is_warned_of() -> None:
    """odohil/session/commands/plan.py ``PlannedExperiment.turn_warning``: on the
    Create 2 (turns carry error) a turn design is named; reverse ones are not."""
    create2 = Path(robots_init).parent / "create2.toml"
    for variant, named in (("turn", True), ("reverse", False)):
        plan = f"k=1,l=1,n=10,variant={variant};k=0.5,l=1,n=10,variant={variant}"
        planned = plan_outcome(PlanRequest(NOMAD150, {}, evaluate=plan, robot=create2))
        assert isinstance(planned, PlannedExperiment)
        warning = planned.turn_warning()
        if named:
            assert warning is not None
            assert warning.startswith("turn designs on a robot whose turns carry error (k=1 l=1")
            assert warning.endswith("the estimate will not be trusted; use variant=reverse")
        else:
            assert warning is None


def test_an_imported_recording_is_written_and_summed_up(tmp_path: Path) -> None:
    """odohil/session/commands/import_log.py ``import_recording``: the trials
    written, their rows per family and direction, the distance driven."""
    log = synth_log(varied_motions())
    path = tmp_path / "log.csv"
    lines = np.arange(2, 2 + len(log.t_s))
    write_csv_log(path, Recording("s", log.t_s, log.odometry, log.truth, lines))
    create2 = Path(robots_init).parent / "create2.toml"
    out = tmp_path / "trials.jsonl"
    summary = import_recording([path], create2, ImportOptions(), out)
    assert summary.table.title == "4 trials from 1 log path, read as csv"
    assert [row[:3] for row in summary.table.rows] == [
        ("straight", "forward", "1"),
        ("spin", "cw", "1"),
        ("straight", "backward", "1"),
        ("arc", "ccw", "1"),
    ]
    assert summary.table.rows[0][3] == "1.000"
    total = sum(t.path.distance_m for t in read_path_trials(out))
    assert summary.wrote == f"wrote 4 trials ({total:.3f} m driven) to {out}"


def test_the_tables_commands_print_are_the_sessions_words(tmp_path: Path) -> None:
    """odohil/session/table_text.py: predict's and covariance's tables
    (commands/design_tables.py), plan's (commands/plan.py, commands/plan_paths.py) and the
    parameters table (text/outcome.py ``parameters_text``): title, column heads
    as wide as every row, the columns of words."""
    design = Design(1, 2.0)
    means = forth_and_back_means(design, NOMAD150)
    predicted = predict_table(design, NOMAD150, means, "paper")
    assert predicted.title == f"Expected observables, forth and back {design.label()} (rho = 4 m)"
    assert predicted.rows == predict_rows(means)
    assert predicted.caption is not None
    assert predicted.caption.endswith(f"(1+E_T = {1.0 + NOMAD150.e_t:g})")
    path = named_path("square", None, None, "turn", 1.0)
    exact, sim = path_moments(path, NOMAD150, 50, 3, 0.05)
    moments = covariance_table(path, NOMAD150, exact, sim, "si")
    assert moments.columns[-1] == "simulated (50 trials) +- MC se"
    assert moments.words == ("quantity",)
    request = PlanRequest(NOMAD150, {"E_R": 0.01}, evaluate="k=1,l=6,n=30;k=20,l=0.5,n=30")
    planned = plan_outcome(request)
    assert isinstance(planned, PlannedExperiment)
    assert planned.designs_table().rows == planned.design_rows()
    errors = planned.errors_table("si")
    assert (errors.caption, errors.rows) == (planned.measurement, planned.error_rows("si"))
    evaluate = "path=square:1,cw,n=10;path=square:1,ccw,n=10"
    create2 = Path(robots_init).parent / "create2.toml"
    scored = plan_outcome(PlanRequest(NOMAD150, {}, evaluate=evaluate, robot=create2))
    assert isinstance(scored, ScoredPaths)
    assert scored.table("paper").rows == scored.rows("paper")
    result = estimate_source([_trial_file(tmp_path, Design(1, 2.0), 12, 2)]).result
    assert result is not None
    shown = parameters_text(result, "si", "estimate")
    assert shown.title == f"estimate ({result.method}, 12 trials)"
    assert (shown.title_left, shown.flagged) == (True, ("NO",))
    assert parameters_text(result).title == "Estimate after 12 trials"
    for table in (predicted, moments, planned.designs_table(), errors, shown):
        assert all(len(row) == len(table.columns) for row in table.rows)
        assert set(table.words) <= set(table.columns)


def test_the_demo_says_where_its_fake_is_and_its_truth(tmp_path: Path) -> None:
    """odohil/session/commands/demo.py ``Demo.heading``, in either unit system."""
    demo = demo_session("nomad150", 1, tmp_path / "demo")
    systems: tuple[units.UnitSystem, ...] = ("paper", "si")
    for system in systems:
        truth = parameters_line(demo.truth, system)
        assert demo.heading(system) == f"fake robot at {demo.port}; its true parameters: {truth}"


def test_the_wizard_guides_a_calibration_unless_told_to_validate(tmp_path: Path) -> None:
    """odohil/session/wizard/dialogue.py ``wizard_spec``: a calibration with
    the operator's tape and the wizard's default plan; ``--path`` without
    ``--validate`` (and no validation session) refused; and the Ctrl-C policy
    that writes to standard error (odohil/session/wizard/interrupts.py ``on_stderr``)."""
    spec, guide = wizard_spec(tmp_path / "s", ROBOT, None, PORT, None, 6.0, False, None, None, None)
    assert guide is None
    assert (spec.folder, spec.mode, spec.robot_path) == (tmp_path / "s", "auto", ROBOT)
    assert (spec.plan, spec.default_plan, spec.measure) == (None, WIZARD_PLAN, OPERATOR)
    assert (spec.allow_few_trials, spec.note) == (True, {"by": "wizard", "port": PORT})
    with pytest.raises(ParameterError, match="--validate"):
        wizard_spec(tmp_path / "t", ROBOT, None, PORT, None, 6.0, False, None, "square:1,cw", 3)
    interrupts = Interrupts.on_stderr(130, 4, "may still be moving")
    assert (interrupts.exits, interrupts.unconfirmed) == ((130, 4), "may still be moving")
