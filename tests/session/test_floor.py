"""Floor-aware choreography: one-way trials come back, the floor length is
respected, and a resumed session starts where its next trial should.

Against the fake robot on a real pseudo-terminal (``python -m fakes.nomad``),
through the console commands, each a process of its own forked from a server
that imported odohil once (tests/forked.py)."""

from __future__ import annotations

import math
import shutil
import signal
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from fakes.nomad.process import EmulatorProcess
from odohil.errors import JournalError
from odohil.session.journal import events as ev
from odohil.session.journal.file import read_journal
from odohil.session.journal.state import load_session_trials
from tests import forked
from tests.session.helpers import write_robot

ODOHIL = shutil.which("odohil") or "odohil"
EMULATOR = ["--time-scale", "20000", "--E-R", "-1", "--K-theta", "0.3", "--K-rho", "0.0009"]


@pytest.fixture
def emulator(tmp_path: Path) -> Iterator[EmulatorProcess]:
    args = [*EMULATOR, "--seed", "5", "--no-pacing", "--truth-socket", str(tmp_path / "t.sock")]
    with EmulatorProcess(args) as process:
        yield process


def _run(emulator: EmulatorProcess, tmp_path: Path, plan: str, *extra: str) -> list[str]:
    return [
        ODOHIL, "run", "--allow-few-trials",
        "--port", emulator.device,
        "--truth-socket", emulator.truth_socket,
        "--robot", str(write_robot(tmp_path)),
        "--plan", plan,
        "--measure", "fake",
        "--session", str(tmp_path / "session"),
        "--json",
        *extra,
    ]  # fmt: skip


def test_one_way_trials_come_back_over_the_same_floor(
    emulator: EmulatorProcess, tmp_path: Path
) -> None:
    # before: four one-way trials of 1 m ended 4 m from where the first started
    start = emulator.truth()
    done = forked.completed(_run(emulator, tmp_path, "k=0.5,l=1,n=4"), timeout=120)
    assert done.returncode == 3, done.stderr  # finished; 4 trials: below the minimum, doubtful
    end = emulator.truth()
    away = math.hypot(end.true_x_m - start.true_x_m, end.true_y_m - start.true_y_m)
    assert away < 0.1, away  # only the odometry error of four 1 m runs
    records = read_journal(tmp_path / "session").records
    driven = [r.data["backward"] for r in records if r.kind == ev.TRIAL_START]
    assert driven == [False, True, False, True]
    # offline re-estimation sees the designs as driven
    trials = load_session_trials(tmp_path / "session")
    assert [t.design.backward for t in trials.trials] == driven


@pytest.fixture
def slow_emulator(tmp_path: Path) -> Iterator[EmulatorProcess]:
    """The fake at a time scale where a 2 m leg lasts about a quarter second."""
    args = [*EMULATOR, "--seed", "5", "--no-pacing", "--truth-socket", str(tmp_path / "t.sock")]
    args[args.index("--time-scale") + 1] = "20"
    with EmulatorProcess(args) as process:
        yield process


def _kinds(tmp_path: Path) -> list[str]:
    try:
        return [r.kind for r in read_journal(tmp_path / "session").records]
    except (OSError, JournalError):
        return []


def test_resume_after_ctrl_c_mid_motion_refuses_unless_from_here(
    slow_emulator: EmulatorProcess, tmp_path: Path
) -> None:
    emulator = slow_emulator
    process = forked.start(_run(emulator, tmp_path, "k=0.5,l=2,n=2")[1:])
    deadline = time.monotonic() + 60
    while ev.MOTION_START not in _kinds(tmp_path):
        assert process.poll() is None, process.communicate()[1]
        assert time.monotonic() < deadline
        time.sleep(0.002)
    while emulator.truth().moving is False and time.monotonic() < deadline:
        time.sleep(0.002)
    time.sleep(0.1)  # well into the 2 m leg
    process.send_signal(signal.SIGINT)
    _, err = process.communicate(timeout=30)
    process.close()
    assert process.returncode == 130, err
    while emulator.truth().moving:
        assert time.monotonic() < deadline
        time.sleep(0.01)
    stood = emulator.truth()

    # before: resume started the trial again from where the robot stood
    resume = [ODOHIL, "resume", str(tmp_path / "session"), "--json"]
    refused = forked.completed(resume, timeout=60)
    assert refused.returncode == 2, refused.stderr
    assert "not where trial 1 starts" in refused.stderr
    assert "heading=" in refused.stderr
    assert "--from-here" in refused.stderr
    after = emulator.truth()
    assert (after.true_x_m, after.true_y_m) == (stood.true_x_m, stood.true_y_m)  # nothing moved
    assert ev.TRIAL_START not in _kinds(tmp_path)[-3:]

    # told to, it goes on from there and completes every trial once
    done = forked.completed([*resume, "--from-here"], timeout=120)
    assert done.returncode == 3, done.stderr  # finished; 2 trials: below the minimum, doubtful
    assert "--from-here" in done.stderr
    records = read_journal(tmp_path / "session").records
    assert sorted(r.data["trial"] for r in records if r.kind == ev.SOLVED) == [1, 2]


def test_run_refuses_a_plan_over_the_floor_before_anything_moves(
    emulator: EmulatorProcess, tmp_path: Path
) -> None:
    robot = tmp_path / "floor.toml"
    robot.write_text(
        write_robot(tmp_path).read_text(encoding="utf-8") + "[floor]\nlength_m = 8.0\n"
    )
    before = emulator.truth()
    args = _run(emulator, tmp_path, "k=1,l=2,n=2;k=0.5,l=12,n=3")
    args[args.index("--robot") + 1] = str(robot)
    done = forked.completed(args, timeout=60)
    assert done.returncode == 2, done.stderr
    assert "plan design 2 (k=0.5 l=12 m turn)" in done.stderr
    assert "length_m is 8 m" in done.stderr
    assert not (tmp_path / "session").exists()
    after = emulator.truth()
    assert (after.true_x_m, after.true_y_m) == (before.true_x_m, before.true_y_m)


def test_floor_length_is_read_checked_and_bounds_the_planner() -> None:
    from odohil.errors import RobotDescriptionError
    from odohil.science.parameters import NOMAD150
    from odohil.science.planner import DEFAULT_FLOOR_M, plan_experiment
    from odohil.science.robot_description import parse_robot_description
    from tests.session.helpers import ROBOT_TOML

    description = parse_robot_description(ROBOT_TOML + "[floor]\nlength_m = 3\n")
    assert description.floor_length_m == 3.0
    assert parse_robot_description(ROBOT_TOML).floor_length_m is None
    for bad in ("0", "-1", "1e9", '"8"', "nan"):
        with pytest.raises(RobotDescriptionError, match=r"floor\.length_m"):
            parse_robot_description(ROBOT_TOML + f"[floor]\nlength_m = {bad}\n")
    with pytest.raises(RobotDescriptionError, match=r"floor\.width_m"):
        parse_robot_description(ROBOT_TOML + "[floor]\nwidth_m = 3\n")
    # before: a 600 m budget gave k=0.5 l=30 n=13, 390 m in one direction
    default = plan_experiment(NOMAD150, 600.0, max_designs=1)
    assert max(item.design.l_m for item in default.items) <= DEFAULT_FLOOR_M
    assert default.excursion_m <= DEFAULT_FLOOR_M
    short = plan_experiment(NOMAD150, 600.0, floor_m=3.0)
    assert short.excursion_m <= 3.0


def test_choreography_cost_does_not_grow_with_the_trial_count() -> None:
    from odohil.session.plans.plan import Plan, parse_plan

    plan = parse_plan("k=0.5,l=2,n=1000000000;k=1,l=3,n=1000000000")
    started = time.monotonic()
    # out and back over 2 m, then the 3 m trials from the first start, forwards
    assert plan.excursion_m == 3.0
    assert [plan.design_of(t).backward for t in (1, 2, 3, 10**9)] == [False, True, False, True]
    assert plan.choreography.trial(10**9 + 1) == (plan.items[1].design, 0.0)
    assert time.monotonic() - started < 1.0
    # sessions journaled before the alternation were all forwards: 40 m for 40 trials
    legacy = Plan(parse_plan("k=0.5,l=1,n=40").items, alternate=False)
    assert legacy.excursion_m == 40.0
    assert Plan.from_json({"designs": legacy.to_json()["designs"]}).excursion_m == 40.0
