"""Shared set-up of the session tests: a robot description, a fake robot in process."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import fakes  # noqa: F401  (registers the fakerobot:// URL handler)
from odohil.driver.nomad.backend import NomadBackend
from odohil.driver.nomad.link import open_port
from odohil.science.floor_marks import MarkDistances
from odohil.science.robot_description import RobotDescription, parse_robot_description

ROBOT_TOML = """\
[screws]
A = [0.20, 0.0]
B = [-0.10, 0.173]
C = [-0.10, -0.173]
[measurement]
sigma_m = 0.001
cross = [["A", "B"], ["B", "C"]]
"""

FINE_TAPE_ROBOT_TOML = ROBOT_TOML.replace("sigma_m = 0.001", "sigma_m = 0.0005")
"""The same robot, measured with a tape of 0.5 mm standard deviation."""

FAST = "time_scale=20000"
"""Fake robot time scale for tests: motions take well under a millisecond."""


def description() -> RobotDescription:
    """The test robot description."""
    return parse_robot_description(ROBOT_TOML, "test robot")


def write_robot(folder: Path) -> Path:
    """The test robot description as a file in ``folder``."""
    path = folder / "robot.toml"
    path.write_text(ROBOT_TOML, encoding="utf-8")
    return path


class PortTruth:
    """The true pose of an in-process fake robot (a fakerobot:// port)."""

    def __init__(self, port: Any) -> None:
        self.port = port

    def true_pose(self) -> tuple[float, float, float]:
        snapshot = self.port.engine.truth()
        return (snapshot.true_x_m, snapshot.true_y_m, snapshot.true_theta_rad)

    def moving(self) -> bool:
        return bool(self.port.engine.truth().moving)


@contextmanager
def fake_robot(query: str) -> Iterator[tuple[NomadBackend, PortTruth]]:
    """A Nomad backend on fakerobot://?QUERY and its truth; closed (st) afterwards."""
    port: Any = open_port(f"fakerobot://?{query}", 38400)
    robot = NomadBackend.from_port(port)
    try:
        yield robot, PortTruth(port)
    finally:
        robot.close()


def readings_of(trial: Any) -> tuple[float, ...]:
    """The readings an open or completed trial's pose was solved from (the
    tape: its distances, metres); () for a source that journals none."""
    return () if trial.readings is None else tuple(trial.readings.values)


@dataclass(frozen=True)
class Heard:
    """A toy pose source's readings (not the tape's): how many times it heard
    something this attempt. What the engine and the journal must carry opaquely."""

    heard: int = 0

    @property
    def values(self) -> tuple[float, ...]:
        return (float(self.heard),)

    def marks(self, description: RobotDescription) -> MarkDistances | None:
        return None


FEW_PATH_TRIALS = (
    "verdict: DOUBTFUL (fewer than 10 trials a path family and direction, the planner's "
    "minimum for honest intervals: "
)
"""How the verdict of a session of general paths below the planner's minimum
trials a family and direction begins (issue 31: as the forth-and-back one)."""


def doubtful_only_for_few_trials(stderr: str) -> bool:
    """Whether the verdict line in ``stderr`` is doubtful for the few trials
    a path family and direction alone (one reason)."""
    said = " ".join(stderr.split())
    if FEW_PATH_TRIALS not in said:
        return False
    reasons = said.split(FEW_PATH_TRIALS, 1)[1].split(")", 1)[0]
    return ";" not in reasons
