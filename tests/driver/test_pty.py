"""The driver over a real pseudo-terminal against ``odohil emulate``."""

from __future__ import annotations

import time

import pytest

from fakes.nomad.process import EmulatorProcess
from odohil.driver.motion import forth_and_back
from odohil.driver.robot import NomadRobot
from odohil.errors import DisconnectedError, OdohilTimeoutError
from odohil.science.paths import Design


def test_forth_and_back_k2_l1_returns_to_start_within_one_wire_unit() -> None:
    with EmulatorProcess(["--seed", "11", "--time-scale", "50"], use_cli=True) as emu:
        with NomadRobot.connect(emu.device) as robot:
            record = forth_and_back(robot, Design(2, 1.0))
        start, end = record.start, record.end
        assert abs(end.x_wire - start.x_wire) <= 1
        assert abs(end.y_wire - start.y_wire) <= 1
        assert end.steer_wire == start.steer_wire
        assert [c.trans for c in record.commands] == [394, 0] * 4
        assert [c.steer for c in record.commands] == [0, 1800] * 4
        truth = emu.truth()
        assert [r.args for r in truth.motion_log if r.command == "pr"] == [
            (c.trans, c.steer, c.turret) for c in record.commands
        ]
        assert not truth.moving
        # The true pose drifted (the odometry error the project calibrates).
        assert (truth.true_x_m, truth.true_y_m) != (0.0, 0.0)


def test_dropped_reply_over_pty_times_out_and_resyncs() -> None:
    with (
        EmulatorProcess(["--seed", "12", "--fault", "drop:gs@2"], use_cli=True) as emu,
        NomadRobot.connect(emu.device) as robot,
    ):
        started = time.monotonic()
        with pytest.raises(OdohilTimeoutError, match="resynced"):
            robot.state()
        assert time.monotonic() - started < 2.5


def test_disconnect_over_pty_is_eio() -> None:
    args = ["--seed", "13", "--time-scale", "20", "--fault", "disconnect"]
    with EmulatorProcess(args, use_cli=True) as emu:
        robot = NomadRobot.connect(emu.device)
        try:
            robot.set_speeds(0.5, 1.0, 1.0)
            robot.set_accelerations(0.5, 1.0, 1.0)
            robot.move_relative(1.0, 0.0)
            started = time.monotonic()
            with pytest.raises(DisconnectedError):
                robot.poll_until_stopped(30.0)
            assert time.monotonic() - started < 2.5
        finally:
            robot.close()
        truth = emu.truth()
        assert [r.command for r in truth.motion_log].count("pr") == 1
        assert truth.disconnected
