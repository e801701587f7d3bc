"""The one session lifecycle (issue 18), in process, over both backends through
their in-process fakes' URL handlers: spec -> pre-flight -> open -> run ->
outcome, each pre-flight failure (its exit class and a message naming the
option and what is accepted, nothing written), and the resume of an
interrupted session."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import pytest
from typer.testing import CliRunner

import fakes
from odohil.cli.app import app
from odohil.cli.exit_codes import EXIT_BAD_INPUT, EXIT_UNTRUSTED, exit_for_check, exit_for_run
from odohil.errors import JournalError
from odohil.robots import __file__ as robots_init
from odohil.science.estimators import EstimateResult
from odohil.session.journal import events as ev
from odohil.session.journal.file import Record, read_journal
from odohil.session.journal.state import SessionState, load_session
from odohil.session.plans.plan import parse_plan
from odohil.session.run import (
    PreflightFailed,
    Prepared,
    SessionSpec,
    final_estimate,
    open_session,
    preflight,
    require,
    run_session,
)
from odohil.session.run.engine import IncrementalLiveEstimator, start_session
from odohil.session.run.start_pose import StartPose

ROBOTS = Path(robots_init).parent
BACKENDS = {
    "nomad150": ("fakerobot://?seed=6&time_scale=100", "k=1,l=1,n=3"),
    "create2": (
        "fakecreate2://?seed=3&time_scale=10&max_gap_ms=15&skip_waits=1",
        "k=0.5,l=0.5,n=3",
    ),
}
"""Each backend's in-process fake and a plan; the Create 2's waits for its next
stream frame skipped (``skip_waits=1``: the same frames at the same simulated
times, without sleeping): no test here times the robot against the wall clock."""
ORDER = [
    "session folder",
    "robot description",
    "plan feasible",
    "plan estimable",
    "exclusions",
    "cross distances",
    "floor space",
    "port",
    "measurement",
]


@pytest.fixture(autouse=True)
def _fake_urls() -> None:
    fakes.register_url_handlers()


def spec_of(tmp_path: Path, backend: str, **changes: object) -> SessionSpec:
    port, plan = BACKENDS[backend]
    spec = SessionSpec(
        tmp_path / "session",
        robot_path=ROBOTS / f"{backend}.toml",
        plan=plan,
        measure="fake",
        port=port,
        seed=1,
        allow_few_trials=True,
    )
    return replace(spec, **changes)  # type: ignore[arg-type]


def anywhere(start: StartPose) -> None:
    """A start check that lets each trial start where the robot stands (a new
    in-process fake stands at the origin)."""


class Seen:
    """An observer: the records and the live estimates, optionally
    interrupting (as Ctrl-C does) after the first solved trial."""

    def __init__(self, interrupt_after: int | None = None) -> None:
        self.kinds: list[str] = []
        self.live: list[EstimateResult] = []
        self.interrupt_after = interrupt_after

    def record(self, record: Record, state: SessionState) -> None:
        self.kinds.append(record.kind)
        if record.kind == ev.SOLVED and len(state.completed) == self.interrupt_after:
            raise KeyboardInterrupt("Ctrl-C")

    def estimated(self, result: EstimateResult, state: SessionState) -> None:
        self.live.append(result)


@pytest.mark.parametrize("backend", list(BACKENDS))
def test_spec_preflight_open_run_outcome(tmp_path: Path, backend: str) -> None:
    spec = spec_of(tmp_path, backend)
    checked = preflight(spec)
    assert [c.name for c in checked.checks] == ORDER
    assert all(c.passed for c in checked.checks), checked.checks
    assert not spec.folder.exists()  # pre-flight writes nothing
    prepared = require(checked)
    assert prepared.line.protocol == backend
    with open_session(prepared) as opened:
        outcome = run_session(opened, Seen(), start_check=anywhere)
    assert outcome.status == "finished"
    assert outcome.stop is None
    state = load_session(spec.folder).state
    assert state.finished
    assert [t.trial for t in outcome.state.completed] == [1, 2, 3]
    # the estimate and verdict are the one recipe's, on the journal
    assert outcome.estimate.status == final_estimate(state).status
    assert outcome.estimate.result is not None
    # three trials: below the planner's minimum, so not trusted (3)
    assert not outcome.estimate.trusted
    assert exit_for_run(outcome) == EXIT_UNTRUSTED


def failures(tmp_path: Path) -> list[tuple[dict[str, object], str, list[str]]]:
    """(changes to the spec, the failing check, words its message must hold)."""
    link = tmp_path / "dangling"
    link.symlink_to(tmp_path / "gone")
    return [
        ({"folder": link}, "session folder", ["--session", "symbolic link", "does not exist"]),
        ({"robot_path": tmp_path / "none.toml"}, "robot description", ["--robot", "none.toml"]),
        ({"plan": "k=1,l=1,n=0"}, "plan feasible", ["--plan", "n", "1"]),
        (
            {"plan": "k=1,l=150,n=3"},
            "plan feasible",
            ["--plan", "l", "at most"],
        ),  # past both robots
        ({"plan": "k=1,l=1,n=1"}, "plan estimable", ["--plan", "becomes estimable with"]),
        (
            {"plan": "k=0.5,l=1,n=3", "allow_few_trials": False},
            "trials per design",
            ["--plan", "10", "--allow-few-trials"],
        ),
        ({"exclude": frozenset({99})}, "exclusions", ["--exclude", "99", "1..3"]),
        ({"port": None}, "port", ["--port", "[serial]"]),
        ({"baud": 1234}, "port", ["baud 1234", "--baud", "give one of"]),
        ({"port": "/dev/odohil-no-such-port"}, "measurement", ["--measure fake", "--truth-socket"]),
        (
            {"measure": str(tmp_path / "none.csv")},
            "measurement",
            ["--measure", "none.csv"],
        ),
    ]


@pytest.mark.parametrize("backend", list(BACKENDS))
def test_each_preflight_failure_is_bad_input_naming_the_option(
    tmp_path: Path, backend: str
) -> None:
    for changes, name, words in failures(tmp_path):
        if backend == "create2" and changes.get("port", "") is None:
            continue  # create2.toml has no [serial] port either: same case
        spec = spec_of(tmp_path, backend, **changes)
        checked = preflight(spec)
        failure = checked.failure
        assert failure is not None, changes
        assert failure.name == name, (changes, failure)
        assert checked.checks[-1] == failure  # the list stops at its first failure
        assert all(c.passed for c in checked.checks[:-1])
        assert failure.exit_class == "bad input"
        assert exit_for_check(failure) == EXIT_BAD_INPUT
        for word in words:
            assert word in failure.message, (changes, failure.message)
        with pytest.raises(PreflightFailed):
            require(checked)
        assert not (tmp_path / "session").exists()  # nothing written


def test_turns_on_a_robot_whose_turns_carry_error_are_refused_unless_allowed(
    tmp_path: Path,
) -> None:
    spec = spec_of(tmp_path, "create2", plan="k=0.5,l=0.5,n=3,variant=turn")
    failure = preflight(spec).failure
    assert failure is not None
    assert failure.name == "plan feasible"
    assert "--allow-turns" in failure.message
    assert "variant=reverse" in failure.message
    allowed = require(preflight(replace(spec, allow_turns=True)))
    assert any("will not be trusted" in w for w in allowed.warnings)


def interrupted_session(tmp_path: Path, backend: str) -> Prepared:
    prepared = require(preflight(spec_of(tmp_path, backend)))
    with open_session(prepared) as opened:
        outcome = run_session(opened, Seen(interrupt_after=1), start_check=anywhere)
    assert outcome.status == "interrupted"
    assert outcome.stop is not None
    assert outcome.stop.robot_stopped
    assert outcome.stop.journaled
    assert exit_for_run(outcome) == 130
    assert [t.trial for t in outcome.state.completed] == [1]
    assert outcome.estimate.result is None  # one trial: no partial estimate yet
    assert outcome.details()["trials_done"] == 1
    return prepared


@pytest.mark.parametrize("backend", list(BACKENDS))
def test_an_interrupted_session_resumes_to_its_outcome(tmp_path: Path, backend: str) -> None:
    prepared = interrupted_session(tmp_path, backend)
    folder = prepared.spec.folder
    resume = SessionSpec(folder, "resume")  # everything else from the journal
    checked = preflight(resume)
    assert checked.failure is None, checked.checks
    again = require(checked)
    assert again.line.port == prepared.line.port
    assert again.plan.to_text() == prepared.plan.to_text()
    with open_session(again) as opened:
        outcome = run_session(opened, Seen(), start_check=anywhere)
    assert outcome.status == "finished"
    assert sorted(t.trial for t in outcome.state.completed) == [1, 2, 3]  # none lost or twice
    assert load_session(folder).state.finished
    kinds = [r.kind for r in read_journal(folder).records]
    assert kinds.count(ev.RESUMED) == 1


def test_a_resumed_session_keeps_its_plan_and_nothing_is_written(tmp_path: Path) -> None:
    prepared = interrupted_session(tmp_path, "nomad150")
    folder = prepared.spec.folder
    before = read_journal(folder).records
    other = preflight(SessionSpec(folder, "auto", plan="k=1,l=1,n=4"))
    assert other.failure is not None
    assert other.failure.name == "plan feasible"
    assert "--plan k=1,l=1,n=4 differs from the session's plan (k=1,l=1,n=3" in (
        other.failure.message
    )
    new = preflight(replace(prepared.spec, mode="new"))
    assert new.failure is not None
    assert new.failure.name == "session folder"
    assert "already holds a session journal" in new.failure.message
    assert read_journal(folder).records == before


def test_a_session_in_use_is_refused_when_opened(tmp_path: Path) -> None:
    prepared = interrupted_session(tmp_path, "nomad150")
    again = require(preflight(SessionSpec(prepared.spec.folder, "resume")))
    with open_session(again), pytest.raises(PreflightFailed) as refused, open_session(again):
        pass
    assert refused.value.check.name == "session"
    assert isinstance(refused.value.__cause__, JournalError)
    assert exit_for_check(refused.value.check) == EXIT_BAD_INPUT


def test_a_new_session_whose_robot_does_not_answer_leaves_no_folder(tmp_path: Path) -> None:
    spec = spec_of(
        tmp_path, "nomad150", port="/dev/odohil-no-such-port", truth_socket=str(tmp_path / "t")
    )
    prepared = require(preflight(spec))
    with pytest.raises(PreflightFailed) as refused, open_session(prepared):
        pass
    assert refused.value.check.name == "robot answers"
    assert "/dev/odohil-no-such-port" in refused.value.check.message
    assert not spec.folder.exists()


@pytest.mark.parametrize("backend", list(BACKENDS))
def test_the_live_estimate_is_the_final_recipe(tmp_path: Path, backend: str) -> None:
    """The wizard's live interval and `estimate`'s on the same trials were two
    recipes (issue 18: E_R [-0.4405, -0.0501] live, [-0.4076, -0.0827] final)."""
    prepared = require(preflight(spec_of(tmp_path, backend)))
    seen = Seen()
    with open_session(prepared) as opened:
        outcome = run_session(opened, seen, start_check=anywhere)
    final = outcome.estimate.result
    assert final is not None
    assert seen.live
    live = seen.live[-1]
    for name in ("E_R", "E_T", "K_theta", "K_rho"):
        assert live.parameter(name).ci95 == final.parameter(name).ci95, name
    assert live.verdict.status == final.verdict.status


def test_the_old_incremental_live_estimate_differs(tmp_path: Path) -> None:
    """What the live estimate was (the Gaussian incremental fit): its intervals
    differ from the recipe's, which is why it is no longer the default."""
    prepared = require(preflight(spec_of(tmp_path, "nomad150")))
    seen = Seen()
    with open_session(prepared) as opened:
        outcome = run_session(
            opened, seen, estimator=IncrementalLiveEstimator(), start_check=anywhere
        )
    final = outcome.estimate.result
    assert final is not None
    assert seen.live
    assert seen.live[-1].parameter("E_R").ci95 != final.parameter("E_R").ci95


def test_resume_refuses_a_wizard_session_before_anything_is_written(tmp_path: Path) -> None:
    """`odohil resume` refuses a session the operator measures (the wizard's)
    as bad input, naming the command that continues it, and writes nothing
    (it exited 1 after locking the session and journaling `resumed`)."""
    folder = tmp_path / "hallway"
    toml = (ROBOTS / "nomad150.toml").read_text(encoding="utf-8")
    journal, _ = start_session(
        folder, toml, parse_plan("k=1,l=6,n=30;k=20,l=0.5,n=30"), measure="operator",
        settings={"port": "/dev/odohil-no-such-port"}, robot_path="robot.toml",
    )  # fmt: skip
    journal.close()
    before = read_journal(folder).records
    failure = preflight(SessionSpec(folder, "resume")).failure
    assert failure is not None
    assert failure.name == "session"
    assert f"odohil wizard --port PORT --session {folder}" in failure.message
    assert exit_for_check(failure) == EXIT_BAD_INPUT
    result = CliRunner().invoke(app, ["resume", str(folder)])
    assert result.exit_code == EXIT_BAD_INPUT, result.output
    assert read_journal(folder).records == before


def test_run_whose_port_does_not_answer_leaves_no_session_folder(tmp_path: Path) -> None:
    """`odohil run` created the session (its journal and plan) before the robot
    answered, so a wrong --port left a folder the next run refused."""
    folder = tmp_path / "s"
    result = CliRunner().invoke(
        app,
        [
            "run", "--port", "/dev/odohil-no-such-port", "--robot", str(ROBOTS / "nomad150.toml"),
            "--plan", "k=0.5,l=1,n=3", "--allow-few-trials", "--measure", "fake",
            "--truth-socket", str(tmp_path / "truth.sock"), "--session", str(folder),
        ],
    )  # fmt: skip
    assert result.exit_code == 1, result.output  # a port that does not answer: an error
    assert "/dev/odohil-no-such-port" in result.output
    assert not folder.exists()
