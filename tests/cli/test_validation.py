"""Bad input is refused before anything moves, with exit 2 and a message that
names the option (or file, column, member) and the accepted range; work stays
bounded (issue 9: checks after the fact, tracebacks, hangs, byte-order mark).

The CLI runs in-process through typer's runner (the same ``app`` the console
script runs); ``run`` gets a port that does not exist, so a check that came
after opening the port would show as exit 1 "cannot open", not exit 2.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner, Result

from odohil.cli.app import app
from odohil.session.journal import events as ev
from odohil.session.journal.file import Journal
from odohil.session.plans.plan import parse_plan

ROBOT_TOML = """\
[screws]
A = [0.20, 0.0]
B = [-0.10, 0.173]
C = [-0.10, -0.173]
[measurement]
sigma_m = 0.001
cross = [["A", "B"]]
"""
NO_PORT = "/dev/odohil-no-such-port"
POSE_HEADER = "k,l_m,variant,dx_m,dy_m,dtheta_rad\n"


def invoke(*args: str) -> Result:
    return CliRunner().invoke(app, list(args))


def flat(result: Result) -> str:
    """The output with rich's box drawing and line breaks taken out."""
    text = result.output
    for mark in "│╭╮╰╯─\n":
        text = text.replace(mark, " ")
    return " ".join(text.split())


def no_traceback(result: Result) -> None:
    assert result.exception is None or isinstance(result.exception, SystemExit), repr(
        result.exception
    )


@pytest.fixture
def robot(tmp_path: Path) -> Path:
    path = tmp_path / "robot.toml"
    path.write_text(ROBOT_TOML)
    return path


def pose_file(path: Path, rows: list[str], prefix: str = "") -> Path:
    path.write_text(prefix + POSE_HEADER + "".join(row + "\n" for row in rows), encoding="utf-8")
    return path


# --- checks after the fact: run validates before any session or port --------


@pytest.mark.parametrize(
    ("plan", "words"),
    [
        ("k=1,l=100,n=3", ["--plan", "l must be", "83.2"]),
        ("k=1,l=0.001,n=3;k=0.5,l=0.001,n=3", ["--plan", "l must be", "0.05"]),
        ("k=1e9,l=1,n=3", ["--plan", "k must be", "500"]),
        ("k=1,l=1,n=100000000", ["--plan", "n must be"]),
    ],
)
def test_run_refuses_a_plan_the_wire_cannot_carry(
    tmp_path: Path, robot: Path, plan: str, words: list[str]
) -> None:
    folder = tmp_path / "session"
    result = invoke("run", "--allow-few-trials",
                    "--port", NO_PORT, "--robot", str(robot), "--plan", plan,
                    "--measure", "fake", "--session", str(folder))  # fmt: skip
    assert result.exit_code == 2, result.output
    for word in words:
        assert word in flat(result)
    assert not folder.exists()


def test_run_refuses_a_trial_file_of_another_design_or_too_short(
    tmp_path: Path, robot: Path
) -> None:
    folder = tmp_path / "session"
    other = pose_file(tmp_path / "other.csv", ["1,2,turn,0,0,0"] * 3)
    short = pose_file(tmp_path / "short.csv", ["1,1,turn,0,0,0"] * 2)
    for trial_file, words in (
        (other, ["row 1", "k=1 l=1 m turn"]),
        (short, ["2 rows for a plan of 3 trials"]),
    ):
        result = invoke("run", "--allow-few-trials",
                        "--port", NO_PORT, "--robot", str(robot), "--plan",
                        "k=1,l=1,n=3", "--measure", str(trial_file),
                        "--session", str(folder))  # fmt: skip
        assert result.exit_code == 2, result.output
        assert "--measure" in flat(result)
        for word in words:
            assert word in flat(result)
        assert not folder.exists()


def test_run_with_valid_input_gets_as_far_as_the_port(tmp_path: Path, robot: Path) -> None:
    good = pose_file(tmp_path / "good.csv", ["1,1,turn,0,0,0"] * 3)
    result = invoke("run", "--allow-few-trials",
                    "--port", NO_PORT, "--robot", str(robot), "--plan", "k=1,l=1,n=3",
                    "--measure", str(good), "--session", str(tmp_path / "s"))  # fmt: skip
    no_traceback(result)
    assert result.exit_code == 1
    assert NO_PORT in flat(result)


def test_session_naming_a_file_is_a_clear_exit_2(tmp_path: Path, robot: Path) -> None:
    a_file = tmp_path / "notes.txt"
    a_file.write_text("not a session")
    result = invoke("run", "--allow-few-trials",
                    "--port", NO_PORT, "--robot", str(robot), "--plan", "k=1,l=1,n=3",
                    "--measure", "fake", "--session", str(a_file))  # fmt: skip
    assert result.exit_code == 2, result.output
    assert "is a file" in flat(result)
    assert "--session" in flat(result)
    resumed = invoke("resume", str(a_file))
    assert resumed.exit_code == 2, resumed.output
    assert "is a file" in flat(resumed)


def _file_session(folder: Path, trial_file: Path, n: int = 3) -> None:
    journal = Journal.create(folder)
    with journal:
        journal.append(
            ev.SESSION,
            {
                "format": ev.FORMAT,
                "robot_toml": ROBOT_TOML,
                "robot_path": "robot.toml",
                "measure": "file",
                "settings": {
                    "port": NO_PORT,
                    "baud": 9600,
                    "seed": 0,
                    "trial_file": str(trial_file),
                },
                "plan": parse_plan(f"k=1,l=1,n={n}").to_json(),
            },
        )


def test_resume_takes_measure_and_checks_it_before_the_port(tmp_path: Path) -> None:
    short = pose_file(tmp_path / "short.csv", ["1,1,turn,0,0,0"] * 2)
    good = pose_file(tmp_path / "good.csv", ["1,1,turn,0,0,0"] * 3)
    folder = tmp_path / "session"
    _file_session(folder, short)
    stuck = invoke("resume", str(folder))
    assert stuck.exit_code == 2, stuck.output
    assert "2 rows for a plan of 3 trials" in flat(stuck)
    fixed = invoke("resume", str(folder), "--measure", str(good))
    no_traceback(fixed)
    assert fixed.exit_code == 1, fixed.output  # got past the checks, to the missing port
    assert NO_PORT in flat(fixed)


# --- tracebacks: every one is now exit 2 naming the problem -----------------


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (("predict", "--k", "1", "--l", "1e300"), ["--l", "at most 100"]),
        (("predict", "--k", "1", "--l", "2", "--E-R", "nan"), ["--E-R", "at most 90"]),
        (("covariance", "--path", "square", "--side", "1e300"), ["--side", "at most 1000"]),
        (("covariance", "--path", "square", "--side", "1e10"), ["--side", "at most 1000"]),
        (
            (
                "covariance",
                "--path",
                "square",
                "--side",
                "100",
                "--simulate",
                "1000000",
                "--segment-m",
                "0.0001",
            ),
            ["segments", "--segment-m"],
        ),
        (("plan", "--budget-m", "1e7"), ["--budget-m", "at most 100000"]),
        (("emulate", "--seed", "-5"), ["--seed", "at least 0"]),
        (("emulate", "--time-scale", "inf"), ["--time-scale"]),
        (("simulate", "--k", "1e9", "--l", "1", "--trials", "2", "--out", "x.csv"), ["--k"]),
    ],
)
def test_out_of_range_options_exit_2_naming_the_option(
    args: tuple[str, ...], words: list[str]
) -> None:
    started = time.monotonic()
    result = invoke(*args)
    assert result.exit_code == 2, result.output
    for word in words:
        assert word in flat(result)
    assert time.monotonic() - started < 10.0


def test_emulate_refuses_a_socket_it_cannot_make(tmp_path: Path) -> None:
    missing = invoke("emulate", "--truth-socket", str(tmp_path / "no" / "such" / "t.sock"))
    assert missing.exit_code == 2, missing.output
    assert "--truth-socket" in flat(missing)
    assert "does not exist" in flat(missing)
    too_long = invoke("emulate", "--truth-socket", str(tmp_path / ("x" * 120)))
    assert too_long.exit_code == 2, too_long.output
    assert "107" in flat(too_long)


@pytest.mark.parametrize(
    ("row", "words"),
    [
        ("1,1,turn,1e300,0,0", ["dx_m", "10000"]),
        ("1e9,1,turn,0,0,0", ["k must be", "500"]),
        ("1e5,1,turn,0,0,0", ["k must be", "500"]),
        ("1,1,turn,0,0," + "1" * 200_000, ["longer than"]),
    ],
)
def test_trial_file_rows_beyond_the_caps_are_refused_quickly(
    tmp_path: Path, row: str, words: list[str]
) -> None:
    trial_file = pose_file(tmp_path / "t.csv", ["1,1,turn,0.01,0,0"] * 8 + [row])
    started = time.monotonic()
    result = invoke("estimate", str(trial_file))
    assert result.exit_code == 2, result.output
    for word in words:
        assert word in flat(result)
    assert time.monotonic() - started < 10.0


def test_robot_description_with_a_tiny_sigma_is_refused(tmp_path: Path) -> None:
    robot = tmp_path / "robot.toml"
    robot.write_text(ROBOT_TOML.replace("sigma_m = 0.001", "sigma_m = 1e-300"))
    trial_file = pose_file(tmp_path / "t.csv", ["1,1,turn,0.01,0,0"] * 8)
    result = invoke("estimate", str(trial_file), "--robot", str(robot))
    assert result.exit_code == 2, result.output
    assert "measurement.sigma_m" in flat(result)
    assert "at least 1e-06" in flat(result)


@pytest.mark.parametrize(
    ("change", "words"),
    [
        ({"plan": [1, 2]}, ["plan must be"]),
        ({"robot_toml": None}, ["robot_toml"]),
        ({"settings": [1]}, ["settings must be"]),
        ({"settings": {"seed": "abc"}}, ["settings.seed"]),
        ({"settings": {"seed": -5}}, ["settings.seed"]),
        ({"measure": 7}, ["measure must be"]),
    ],
)
def test_a_crc_valid_journal_with_a_malformed_header_is_refused(
    tmp_path: Path, change: dict[str, object], words: list[str]
) -> None:
    folder = tmp_path / "session"
    header: dict[str, object] = {
        "format": ev.FORMAT,
        "robot_toml": ROBOT_TOML,
        "measure": "fake",
        "settings": {"port": NO_PORT, "seed": 1},
        "plan": parse_plan("k=1,l=1,n=3").to_json(),
    }
    header.update(change)
    if header["robot_toml"] is None:
        del header["robot_toml"]
    with Journal.create(folder) as journal:
        journal.append(ev.SESSION, header)
    for args in (("resume", str(folder)), ("estimate", str(folder)),
                 ("report", str(folder), "--out", str(tmp_path / "r"))):  # fmt: skip
        result = invoke(*args)
        no_traceback(result)
        assert result.exit_code == 2, (args, result.output)
        for word in words:
            assert word in flat(result), (args, result.output)


# --- byte-order mark ---------------------------------------------------------


def test_a_byte_order_mark_is_accepted(tmp_path: Path) -> None:
    # trials the model could have made (two designs, simulated at seed 1): the
    # fit converges at once (rows of made-up numbers kept the robust fit
    # grinding for 4 s of CPU per estimate, three times)
    rows: list[str] = []
    for k, l_m in (("1", "1"), ("0.5", "2")):
        out = tmp_path / f"simulated-{k}.csv"
        made = invoke("simulate", "--k", k, "--l", l_m, "--trials", "6", "--seed", "1",
                      "--out", str(out))  # fmt: skip
        assert made.exit_code == 0, flat(made)
        rows += out.read_text(encoding="utf-8").splitlines()[1:]
    with_mark = pose_file(tmp_path / "excel.csv", rows, prefix="\ufeff")
    plain = invoke("estimate", str(pose_file(tmp_path / "plain.csv", rows)), "--json")
    assert plain.exit_code == 3, flat(plain)  # 6 trials a design: below the planner's 10
    assert '"fewer than 10 trials a design' in plain.output
    marked = invoke("estimate", str(with_mark), "--json")
    assert "unknown column" not in flat(marked)
    assert marked.exit_code == plain.exit_code
    assert marked.output == plain.output


# --- bounded work --------------------------------------------------------------


@pytest.mark.slow
def test_the_planner_work_grows_with_the_log_of_the_budget() -> None:
    from odohil.science.parameters import NOMAD150
    from odohil.science.planner import plan_experiment

    started = time.monotonic()
    plan = plan_experiment(NOMAD150, 1e7)  # walked one trial at a time: over 300 s
    assert time.monotonic() - started < 60.0
    assert plan.distance_m <= 1e7
    assert plan.n_trials > 1000


def test_the_largest_design_costs_a_bounded_time() -> None:
    from odohil.errors import ParameterError
    from odohil.science.moments import pose_moments
    from odohil.science.parameters import ErrorParameters
    from odohil.science.paths import Design

    hardest = ErrorParameters.from_paper_units(90.0, 0.9, 1000.0, 1.0)
    started = time.monotonic()
    for design in (Design(500, 10.0), Design(50, 100.0), Design(250, 20.0, "reverse")):
        moments = pose_moments(design.path(), hardest)
        assert np.all(np.isfinite(moments.cov))
    assert time.monotonic() - started < 10.0
    for k, l_m in ((1e9, 1.0), (1e5, 1.0), (1.0, 1e300), (500.0, 100.0)):
        with pytest.raises(ParameterError):
            Design(k, l_m)
