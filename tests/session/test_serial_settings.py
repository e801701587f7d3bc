"""robot.toml's ``[serial]`` is used: ``--port`` and ``--baud`` are optional when
the file gives them, the command line overrides, and the banner says which
values are in force and where each came from (issue 10). Commands in process
(typer's CliRunner on odohil.cli.app's app), against the emulator on its pty."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest
from typer.testing import CliRunner

from fakes.nomad.process import EmulatorProcess
from odohil.cli.app import app
from odohil.errors import ParameterError
from odohil.science.robot_description import parse_robot_description
from odohil.session.journal import events as ev
from odohil.session.journal.file import read_journal
from odohil.session.robots.line import resolve_line
from odohil.session.robots.registry import open_robot
from tests.session.helpers import ROBOT_TOML


@pytest.fixture
def emulator_9600(tmp_path: Path) -> Iterator[EmulatorProcess]:
    args = [
        "--time-scale", "20000", "--seed", "3", "--baud", "9600",
        "--truth-socket", str(tmp_path / "t.sock"),
    ]  # fmt: skip
    with EmulatorProcess(args) as process:
        yield process


def _robot_file(tmp_path: Path, serial: str) -> Path:
    path = tmp_path / "robot.toml"
    path.write_text(ROBOT_TOML + serial, encoding="utf-8")
    return path


def test_run_connects_at_the_files_baud_without_port_or_baud(
    tmp_path: Path, emulator_9600: EmulatorProcess
) -> None:
    robot = _robot_file(tmp_path, f'[serial]\nport = "{emulator_9600.device}"\nbaud = 9600\n')
    args = [
        "run", "--allow-few-trials", "--robot", str(robot), "--plan", "k=1,l=1,n=2",
        "--measure", "fake", "--truth-socket", emulator_9600.truth_socket,
        "--session", str(tmp_path / "s"), "--seed", "2",
    ]  # fmt: skip
    done = CliRunner().invoke(app, args)  # in process: the pty at 9600 baud is the point
    # two trials of the emulator at seed 3, tape seed 2: finished, doubtful (fewer
    # than the planner's minimum trials a design)
    assert done.exit_code == 3, done.stderr
    assert "fewer than 10 trials a design" in done.stderr.replace("\n", " ")
    banner = f"{emulator_9600.device} ({robot} [serial]) at 9600 baud ({robot} [serial])"
    assert banner in done.stderr.replace("\n", ""), done.stderr
    records = read_journal(tmp_path / "s").records
    connection = next(r.data["connection"] for r in records if r.kind == ev.ROBOT)
    assert (connection["port"], connection["baud"]) == (emulator_9600.device, 9600)
    assert any(r.kind == ev.SOLVED for r in records)


def test_the_backend_opens_the_line_at_the_files_baud(emulator_9600: EmulatorProcess) -> None:
    text = ROBOT_TOML + f'[serial]\nport = "{emulator_9600.device}"\nbaud = 9600\n'
    line = resolve_line(parse_robot_description(text), None, None)
    assert (line.port, line.baud, line.baud_from) == (
        emulator_9600.device,
        9600,
        "robot.toml [serial]",
    )
    with open_robot(line.protocol, line.port, line.baud) as robot:
        assert getattr(robot, "transport").baudrate == 9600  # noqa: B009
        assert not robot.odometry().moving


def test_the_command_line_overrides_the_file() -> None:
    text = ROBOT_TOML + '[serial]\nport = "/dev/ttyUSB9"\nbaud = 9600\n'
    line = resolve_line(parse_robot_description(text), "/dev/ttyS1", 19200, "r.toml")
    assert line.describe() == "nomad150 on /dev/ttyS1 (--port) at 19200 baud (--baud)"
    journaled = {"port": "/dev/ttyACM0", "baud": 4800}
    resumed = resolve_line(parse_robot_description(text), None, None, "r.toml", journaled)
    assert (resumed.port_from, resumed.baud_from) == ("the session's journal",) * 2
    bare = resolve_line(parse_robot_description(text.replace("baud = 9600\n", "")), None, None)
    assert (bare.baud, bare.baud_from) == (38400, "nomad150 default")


def test_no_port_anywhere_names_both_ways_to_give_one(tmp_path: Path) -> None:
    with pytest.raises(ParameterError, match=r"--port.*\[serial\]"):
        resolve_line(parse_robot_description(ROBOT_TOML), None, None)
    done = CliRunner().invoke(
        app,
        [
            "run",
            "--allow-few-trials",
            "--robot",
            str(_robot_file(tmp_path, "")),
            "--plan",
            "k=1,l=1,n=2",
            "--measure",
            "fake",
            "--session",
            str(tmp_path / "s"),
        ],
    )
    assert done.exit_code == 2
    assert "--port" in done.stderr
    assert not (tmp_path / "s").exists()


def test_an_unknown_robot_protocol_is_refused_before_anything_moves(tmp_path: Path) -> None:
    robot = _robot_file(tmp_path, '[robot]\nprotocol = "roomba9000"\n')
    done = CliRunner().invoke(
        app,
        [
            "run",
            "--allow-few-trials",
            "--port",
            "/dev/null",
            "--robot",
            str(robot),
            "--plan",
            "k=0.5,l=1,n=2",
            "--measure",
            "fake",
            "--truth-socket",
            str(tmp_path / "t.sock"),
            "--session",
            str(tmp_path / "s"),
        ],
    )
    assert done.exit_code == 2, done.stderr
    assert "'roomba9000'" in done.stderr
    assert "nomad150" in done.stderr  # the installed backends are named
    assert not (tmp_path / "s").exists()


def test_a_baud_the_robot_does_not_speak_is_refused_before_the_port_opens() -> None:
    text = ROBOT_TOML + '[serial]\nport = "/dev/odohil-no-such-port"\n'
    with pytest.raises(ParameterError, match=r"baud 57600 \(--baud\).*4800, 9600, 19200, 38400"):
        resolve_line(parse_robot_description(text), None, 57600)
