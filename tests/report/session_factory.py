"""Build a real session with the engine against the in-process fake robot."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import serial

import fakes  # noqa: F401  (registers fakerobot://)
from odohil.driver.nomad.backend import NomadBackend
from odohil.science.robot_description import RobotDescription
from odohil.session.journal.state import SessionState
from odohil.session.measure.protocol import TrialContext
from odohil.session.measure.tape.distances import FakeTruthSource
from odohil.session.measure.tape.records import TapeContext
from odohil.session.measure.tape.source import TapeSource
from odohil.session.plans.plan import parse_plan
from odohil.session.run.engine import (
    IncrementalLiveEstimator,
    MotionSettings,
    SessionEngine,
    description_of,
    start_session,
)
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


class KeptSlips(FakeTruthSource):
    """The fake's distances, but from trial ``first`` on the operator types one
    distance (``trial % m``) 10 mm too long on the first reading of an attempt,
    and when the slip check doubts the trial keeps the value (a flagged trial)."""

    def __init__(self, *args: Any, first: int, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.first = first

    def distance(self, ctx: TapeContext, index: int) -> float:
        """The fake's distance, typed 10 mm long on the chosen trials' first reading."""
        value = super().distance(ctx, index)
        slip = ctx.trial >= self.first and ctx.rejections == 0
        return value + 0.01 if slip and index == ctx.trial % len(ctx.labels) else value

    def remeasure(  # type: ignore[override]  # the source protocol allows None
        self, ctx: TapeContext, index: int, reason: str
    ) -> None:
        """The operator keeps the value taken."""
        return None


def build_session(
    folder: Path,
    plan_text: str,
    seed: int = 3,
    bump: tuple[int, float] | None = None,
    kept_slips_from: int | None = None,
    robot_toml: str = ROBOT_TOML,
) -> SessionState:
    """Run a whole session of ``plan_text`` against fakerobot:// (fast clock);
    ``bump``: (trial, metres) that trial's end marks are moved across the path;
    ``kept_slips_from``: from this trial on the operator types one distance
    10 mm long and keeps it when the slip check doubts it (see :class:`KeptSlips`)."""
    plan = parse_plan(plan_text)
    journal, state = start_session(folder, robot_toml, plan, measure="fake", settings={})
    port = serial.serial_for_url(f"fakerobot://?seed={seed}&time_scale=2000", timeout=0.5)
    with journal, NomadBackend.from_port(port) as robot:
        engine = SessionEngine(
            journal,
            state,
            robot,
            TapeSource(
                _source(PortTruth(port), description_of(state), seed, bump, kept_slips_from),
                description_of(state),
            ),
            estimator=IncrementalLiveEstimator(),
            motion=MotionSettings(speeds=(1.0, 3.0), accelerations=(2.0, 6.0), watchdog_s=0.0),
        )
        return engine.run()


def _source(
    truth: PortTruth,
    description: RobotDescription,
    seed: int,
    bump: tuple[int, float] | None,
    kept_slips_from: int | None,
) -> FakeTruthSource:
    if bump is not None:
        return BumpedSource(truth, description, seed=seed, bump=bump)
    if kept_slips_from is not None:
        return KeptSlips(truth, description, seed=seed, first=kept_slips_from)
    return FakeTruthSource(truth, description, seed=seed)
