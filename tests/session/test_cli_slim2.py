"""What the CLI used to decide itself and now asks the session layer for
(issue 18, "the CLI parses, calls and renders"; tests/session/test_cli_slim.py
for the first round), in process over the fake Nomad's URL handler:
``odohil validate``'s spec of a driven validation session, the finished one it
tests again without driving, the options a trial file does not use
(odohil/session/commands/validate.py); the wizard's put-back answer
(odohil/session/run/start_pose.py); how a run that did not finish is told
(odohil/session/text/run.py); what ``odohil plan`` prints of a plan
(odohil/session/commands/plan.py); the rows of predict and covariance
(odohil/session/commands/design.py); what report writes
(odohil/session/commands/report.py); the live E_R and the demo's truth;
emulate's line; simulate's fresh seed."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import pytest

import fakes
from odohil.errors import JournalError, ParameterError
from odohil.robots import __file__ as robots_init
from odohil.science.closed_forms import forth_and_back_means
from odohil.science.parameters import NOMAD150
from odohil.science.paths import Design
from odohil.science.simulator import simulate
from odohil.session.commands.demo import demo_session
from odohil.session.commands.design import (
    covariance_rows,
    fresh_seed,
    path_moments,
    predict_rows,
    write_simulated_trials,
)
from odohil.session.commands.plan import PlannedExperiment, PlanRequest, trial_minutes
from odohil.session.commands.plan_paths import plan_outcome
from odohil.session.commands.report import session_report, write_any_report
from odohil.session.commands.validate import (
    CalibrationRobot,
    check_file_options,
    journaled_trials,
    validation_spec,
)
from odohil.session.plans.plan import Plan, PlanItem
from odohil.session.results.outcome import Selection, estimate_source
from odohil.session.results.validation import parse_validation_path
from odohil.session.robots.registry import emulated_line, emulator, parse_description
from odohil.session.run import open_session, preflight, require, run_session
from odohil.session.run.engine import StopOutcome
from odohil.session.run.start_pose import StartPose, put_back
from odohil.session.text.outcome import live_e_r
from odohil.session.text.run import MAY_STILL_MOVE, Said, error_said, resuming, run_ended
from odohil.session.trials.logs import ImportOptions

ROBOT = Path(robots_init).parent / "nomad150.toml"
PORT = "fakerobot://?seed=2&time_scale=2000"


@pytest.fixture(autouse=True)
def _fake_urls() -> None:
    fakes.register_url_handlers()


def _robot() -> CalibrationRobot:
    toml = ROBOT.read_text(encoding="utf-8")
    return CalibrationRobot(parse_description(toml, str(ROBOT)), toml, str(ROBOT))


def _anywhere(start: StartPose) -> None:
    """Each trial starts where the in-process fake stands."""


def test_a_driven_validation_needs_trials_and_a_measure(tmp_path: Path) -> None:
    vpath = parse_validation_path("forth-back:1,0.5")
    folder, calibration = tmp_path / "v", tmp_path / "calibration"
    with pytest.raises(ParameterError, match=r"--trials N is needed"):
        validation_spec(folder, vpath, calibration, _robot(), None, "fake")
    with pytest.raises(ParameterError, match=r"--measure is needed to drive: `fake`"):
        validation_spec(folder, vpath, calibration, _robot(), 2, None)
    spec = validation_spec(folder, vpath, calibration, _robot(), 2, "fake")
    assert (spec.folder, spec.mode, spec.purpose, spec.measure) == (
        folder,
        "new",
        "validate",
        "fake",
    )
    assert spec.robot_path == ROBOT
    assert spec.robot_toml == ROBOT.read_text(encoding="utf-8")
    assert spec.settings == {
        "validation_of": str(calibration.resolve()),
        "validation_path": "forth-back:1,0.5",
    }
    assert vpath.design is not None
    assert spec.plan == Plan((PlanItem(vpath.design, 2),))


def test_a_finished_validation_is_tested_again_and_another_refused(tmp_path: Path) -> None:
    vpath = parse_validation_path("forth-back:1,0.5")
    folder = tmp_path / "v"
    assert journaled_trials(folder, vpath) is None  # nothing journaled yet: drive
    spec = validation_spec(folder, vpath, tmp_path / "calibration", _robot(), 2, "fake")
    spec = replace(spec, port=PORT, seed=1)
    with open_session(require(preflight(spec))) as opened:
        assert opened.state.completed == ()  # left unfinished: nothing run
    with pytest.raises(JournalError, match=r"an unfinished validation session: give --out "):
        journaled_trials(folder, vpath)
    with open_session(require(preflight(replace(spec, mode="resume")))) as opened:
        outcome = run_session(opened, start_check=_anywhere)
    assert outcome.status == "finished", outcome.message
    again = journaled_trials(folder, vpath)
    assert again is not None
    assert (len(again), again.source) == (2, str(folder))
    with pytest.raises(JournalError, match=r"holds another validation session: give --out"):
        journaled_trials(folder, parse_validation_path("forth-back:2,0.5"))


def test_a_trial_file_takes_no_port_and_no_measure(tmp_path: Path) -> None:
    vpath = parse_validation_path(f"file:{tmp_path / 'held-out.csv'}")
    check_file_options(vpath, None, None)
    check_file_options(parse_validation_path("square:1"), "/dev/ttyUSB0", "fake")  # driven
    for port, measure in (("/dev/ttyUSB0", None), (None, "fake")):
        with pytest.raises(ParameterError, match=r"reads its trials from the file: --port and"):
            check_file_options(vpath, port, measure)


def test_the_operator_puts_the_robot_back_or_starts_here(tmp_path: Path) -> None:
    """The wizard's put-back answer (odohil/session/run/start_pose.py ``put_back``):
    ``here`` leaves the encoders; anything else sets them to the trial's start."""
    spec = validation_spec(
        tmp_path / "v", parse_validation_path("forth-back:1,0.5"), tmp_path, _robot(), 2, "fake"
    )
    start = StartPose(2, (0.5, -0.02, 0.1), (0.0, 0.0, 0.0))
    with open_session(require(preflight(replace(spec, port=PORT)))) as opened:
        said = put_back(start, " Here ", opened.robot)
        assert said == "The trial starts where the robot stands."
        reading = opened.robot.odometry()
        assert (reading.x_m, reading.y_m) == pytest.approx((0.0, 0.0), abs=1e-3)
        assert put_back(start, "", opened.robot) == "Encoders set to the trial's start."
        reading = opened.robot.odometry()
        assert (reading.x_m, reading.y_m, reading.theta_rad) == pytest.approx(
            (0.5, -0.02, 0.1), abs=3e-3
        )


def test_how_a_run_that_did_not_finish_is_told(tmp_path: Path) -> None:
    """odohil/session/text/run.py ``run_ended``: what ended the run, the robot's
    stop (confirmed or not), the journal and the command that continues; and
    ``resuming``: where a resumed session stands."""
    spec = validation_spec(
        tmp_path / "v", parse_validation_path("forth-back:1,0.5"), tmp_path, _robot(), 2, "fake"
    )
    with open_session(require(preflight(replace(spec, port=PORT, seed=1)))) as opened:
        done = run_session(opened, start_check=_anywhere)
    folder = done.folder
    assert resuming(folder, done.state) == f"resuming {folder}: 2 of 2 trials done"
    stopped = StopOutcome(True, "x=+0.000 m", journaled=True)
    cut = replace(done, status="interrupted", stop=stopped, message="Ctrl-C", signal=2)
    assert run_ended(cut) == [
        Said("note", "interrupted", " (Ctrl-C)"),
        Said("plain", "robot stopped (it reports x=+0.000 m)"),
        Said("plain", f"session journaled in {folder}; continue with `odohil resume {folder}`"),
    ]
    lost = StopOutcome(False, "no reply to st", journaled=False, journal_error="disk full")
    failed = replace(done, status="error", stop=lost, message="the port went away")
    assert run_ended(failed, "odohil wizard --session S", "Interrupted") == [
        error_said("the port went away"),
        Said("alarm", MAY_STILL_MOVE, ": no reply to st"),
        Said(
            "alarm",
            "the journal could not be written",
            f": disk full; the records before this failure are kept in {folder}; free the "
            "disk, then `odohil wizard --session S`",
        ),
    ]
    unconfirmed = replace(done, status="stop unconfirmed", message="no answer", cause="Ctrl-C")
    assert run_ended(unconfirmed) == [
        Said("alarm", f"WARNING: {MAY_STILL_MOVE}"),
        Said("plain", "the run ended on: Ctrl-C"),
        Said("plain", "st sent but not confirmed: no answer"),
    ]


def test_what_plan_prints_of_an_evaluated_plan() -> None:
    """odohil/session/commands/plan.py PlannedExperiment: the designs' rows, the
    errors' rows in either unit system, the time and the verdict in words."""
    request = PlanRequest(NOMAD150, {"E_R": 0.01}, evaluate="k=1,l=6,n=30;k=20,l=0.5,n=30")
    planned = plan_outcome(request)
    assert isinstance(planned, PlannedExperiment)
    assert planned.design_rows() == [
        ("1", "6", "turn", "30", "360", f"{trial_minutes(planned.plan, 0):.0f}"),
        ("20", "0.5", "turn", "30", "600", f"{trial_minutes(planned.plan, 1):.0f}"),
    ]
    paper, si = planned.error_rows("paper"), planned.error_rows("si")
    assert [row[0] for row in paper] == ["E_R", "E_T", "K_theta", "K_rho"]
    assert paper[0][1] == "-0.202"  # deg/m
    assert si[0][1] == f"{math.radians(-0.202):.4g}"  # rad/m
    assert paper[0][3].startswith("0.01 (")  # given
    assert paper[1][3].split(" ")[1] == "default"
    assert planned.time_lines()[0].startswith("operator time: about ")
    assert planned.time_lines()[1].startswith("free floor needed: ")
    meets = planned.plan.meets_targets
    assert planned.verdict().startswith("The plan meets" if meets else "The plan does NOT meet")


def test_the_rows_of_predict_and_covariance() -> None:
    """odohil/session/commands/design.py: predict's rows (phi1 and phi2 also in
    degrees) and covariance's (the simulated column only when simulated)."""
    design = Design(1, 2.0)
    means = forth_and_back_means(design, NOMAD150)
    rows = predict_rows(means)
    assert [row[0] for row in rows] == list(means.as_dict())
    assert rows[0] == (
        "phi1",
        "mean heading change",
        f"{means.phi1:.6g}",
        "rad",
        f"{math.degrees(means.phi1):.6g} deg",
    )
    assert rows[2][4] == ""  # phi3: metres only
    exact, sim = path_moments(design.path(), NOMAD150, None, None, 0.01)
    assert sim is None
    closed = covariance_rows(exact, None)
    assert {len(row) for row in closed} == {2}
    assert closed[0] == ("mean x (m)", f"{exact.mean[0]:.6g}")
    exact, sim = path_moments(design.path(), NOMAD150, 50, 1, 0.01)
    assert {len(row) for row in covariance_rows(exact, sim)} == {3}


def test_what_report_writes_of_a_session_and_of_a_trial_file(tmp_path: Path) -> None:
    """odohil/session/commands/report.py: a session folder gets its own report
    (not when a path family is chosen); a trial file the summary page; both
    with the exports beside."""
    trials, design = tmp_path / "trials.csv", Design(1, 2.0)
    poses = simulate(design.path(), NOMAD150, 12, seed=2, segment_m=0.01).pose_change
    write_simulated_trials(trials, design, poses)
    assert session_report([trials], (), ImportOptions(), Selection()) is None
    outcome = estimate_source([trials])
    files = write_any_report(outcome, tmp_path / "file-report", "trials.csv")
    assert files[-1] == tmp_path / "file-report" / "index.html"
    assert tmp_path / "file-report" / "parameters.json" in files
    spec = validation_spec(
        tmp_path / "v", parse_validation_path("forth-back:1,0.5"), tmp_path, _robot(), 2, "fake"
    )
    with open_session(require(preflight(replace(spec, port=PORT, seed=1)))) as opened:
        assert run_session(opened, start_check=_anywhere).status == "finished"
    chosen = Selection(family="straight")
    assert session_report([spec.folder], (), ImportOptions(), chosen) is None
    report = session_report([spec.folder], (), ImportOptions(), Selection())
    assert report is not None
    assert report.outcome is not None
    assert len(report.outcome.trials) == 2
    files = write_any_report(report, tmp_path / "session-report", "v")
    assert [f.name for f in files][-1] == "index.html"


def test_the_live_e_r_and_the_demo_truth(tmp_path: Path) -> None:
    """odohil/session/text/outcome.py ``live_e_r`` (beside the progress bar, in
    either unit system) and odohil/session/commands/demo.py ``truth_document`` (demo --json)."""
    trials, design = tmp_path / "trials.csv", Design(1, 2.0)
    poses = simulate(design.path(), NOMAD150, 12, seed=2, segment_m=0.01).pose_change
    write_simulated_trials(trials, design, poses)
    result = estimate_source([trials]).result
    assert result is not None
    e_r = result.parameter("E_R").value
    assert live_e_r(result, "paper") == f"E_R {math.degrees(e_r):+.4g} deg/m"
    assert live_e_r(result, "si") == f"E_R {e_r:+.4g} rad/m"
    demo = demo_session("nomad150", 1, tmp_path / "demo")
    document = demo.truth_document()
    assert document["truth"]["E_R"] == {"value": demo.truth["E_R"], "unit": "rad/m"}
    assert set(document["truth"]) == {"E_R", "E_T", "K_theta", "K_rho"}


def test_the_emulated_line_is_the_robots_own_unless_given() -> None:
    """odohil/session/robots/registry.py ``emulated_line``: emulate's baud and time scale."""
    facts, hooks, _ = emulator("nomad150")
    assert emulated_line(facts, hooks, None, None) == (
        facts.default_baud,
        hooks.emulate_time_scale,
    )
    assert emulated_line(facts, hooks, 9600, 20.0) == (9600, 20.0)
    with pytest.raises(ParameterError, match=r"the Nomad 150 speaks 4800, 9600, 19200, 38400"):
        emulated_line(facts, hooks, 115200, None)


def test_a_fresh_seed_is_a_nonnegative_63_bit_number() -> None:
    """odohil/session/commands/design.py ``fresh_seed``: simulate's seed given none."""
    seeds = {fresh_seed() for _ in range(4)}
    assert len(seeds) == 4
    assert all(0 <= seed < 2**63 for seed in seeds)
