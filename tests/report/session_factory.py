"""Build a real session with the engine against the in-process fake robot."""

from __future__ import annotations

from pathlib import Path

import serial

import fakes  # noqa: F401  (registers fakerobot://)
from odohil.driver.robot import NomadRobot
from odohil.session.engine import (
    IncrementalLiveEstimator,
    MotionSettings,
    SessionEngine,
    description_of,
    start_session,
)
from odohil.session.plan import parse_plan
from odohil.session.sources import FakeTruthSource
from odohil.session.state import SessionState
from tests.session.helpers import FINE_TAPE_ROBOT_TOML as ROBOT_TOML


class PortTruth:
    """The fakerobot:// port's truth as a :class:`TruthReader`."""

    def __init__(self, port: serial.Serial) -> None:
        self.port = port

    def true_pose(self) -> tuple[float, float, float]:
        snap = self.port.truth()
        return (snap.true_x_m, snap.true_y_m, snap.true_theta_rad)


def build_session(folder: Path, plan_text: str, seed: int = 3) -> SessionState:
    """Run a whole session of ``plan_text`` against fakerobot:// (fast clock)."""
    plan = parse_plan(plan_text)
    journal, state = start_session(folder, ROBOT_TOML, plan, measure="fake", settings={})
    port = serial.serial_for_url(f"fakerobot://?seed={seed}&time_scale=2000", timeout=0.5)
    with journal, NomadRobot.from_port(port) as robot:
        engine = SessionEngine(
            journal,
            state,
            robot,
            FakeTruthSource(PortTruth(port), description_of(state), seed=seed),
            estimator=IncrementalLiveEstimator(),
            motion=MotionSettings(speeds=(1.0, 3.0), accelerations=(2.0, 6.0), watchdog_s=0.0),
        )
        return engine.run()
