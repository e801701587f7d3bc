"""Build a real session with the engine against the in-process fake robot."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import serial

import fakes  # noqa: F401  (registers fakerobot://)
from odohil.driver.nomad.backend import NomadBackend
from odohil.session.engine import (
    IncrementalLiveEstimator,
    MotionSettings,
    SessionEngine,
    description_of,
    start_session,
)
from odohil.session.plan import parse_plan
from odohil.session.sources import FakeTruthSource, TrialContext
from odohil.session.state import SessionState
from tests.session.helpers import FINE_TAPE_ROBOT_TOML as ROBOT_TOML


class PortTruth:
    """The fakerobot:// port's truth as a :class:`TruthReader`."""

    def __init__(self, port: serial.Serial) -> None:
        self.port = port

    def true_pose(self) -> tuple[float, float, float]:
        snap = self.port.truth()
        return (snap.true_x_m, snap.true_y_m, snap.true_theta_rad)


class BumpedSource(FakeTruthSource):
    """The fake's distances, but trial ``trial``'s end marks were made ``dy_m``
    metres across the path from where the robot stood (a bumped robot): the
    distances agree with one another and with a wrong pose."""

    def __init__(self, *args: Any, bump: tuple[int, float], **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.bump = bump

    def true_pose_change(self, ctx: TrialContext) -> tuple[float, float, float]:
        """The true pose change, bumped on the chosen trial."""
        x, y, theta = super().true_pose_change(ctx)
        trial, dy_m = self.bump
        return (x, y + dy_m, theta) if ctx.trial == trial else (x, y, theta)


def build_session(
    folder: Path, plan_text: str, seed: int = 3, bump: tuple[int, float] | None = None
) -> SessionState:
    """Run a whole session of ``plan_text`` against fakerobot:// (fast clock);
    ``bump``: (trial, metres) that trial's end marks are moved across the path."""
    plan = parse_plan(plan_text)
    journal, state = start_session(folder, ROBOT_TOML, plan, measure="fake", settings={})
    port = serial.serial_for_url(f"fakerobot://?seed={seed}&time_scale=2000", timeout=0.5)
    with journal, NomadBackend.from_port(port) as robot:
        engine = SessionEngine(
            journal,
            state,
            robot,
            (
                FakeTruthSource(PortTruth(port), description_of(state), seed=seed)
                if bump is None
                else BumpedSource(PortTruth(port), description_of(state), seed=seed, bump=bump)
            ),
            estimator=IncrementalLiveEstimator(),
            motion=MotionSettings(speeds=(1.0, 3.0), accelerations=(2.0, 6.0), watchdog_s=0.0),
        )
        return engine.run()
