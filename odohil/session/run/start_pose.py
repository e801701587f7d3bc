"""Is the robot where the session's next trial must start?

Every trial attempt zeroes the encoders where it starts (``dp 0 0``,
``da 0 0``), so the journal says where the encoders should read when the
next trial begins:

- an attempt cut off before or during its motion (open, or voided since):
  at the origin (0, 0, 0) of that attempt, where it started;
- an attempt whose motion finished (measuring or solved): at its encoder end
  pose, where the next trial starts;
- no attempt yet: anywhere (nothing to compare).

A robot further than :data:`POSITION_TOLERANCE_M` or turned more than
:data:`HEADING_TOLERANCE_DEG` from there (after a Ctrl-C mid-motion, or
moved by hand) is not at the trial's start. If the encoders were reset (the
robot was switched off) the comparison is meaningless; the operator knows.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from odohil.driver.odometry import OdometrySample
from odohil.errors import SafetyError
from odohil.science.frames import Pose
from odohil.session.journal.state import Phase, SessionState
from odohil.session.robots.protocol import Robot
from odohil.units import wrap_angle

POSITION_TOLERANCE_M = 0.02
"""How far (metres) the encoders may read from the trial's start."""
HEADING_TOLERANCE_DEG = 2.0
"""How far (degrees) the encoder heading may be from the trial's start."""
HERE = "here"
"""What the operator types to start a trial where the robot stands."""


def pose_text(pose: Pose) -> str:
    """``x=+1.999 m y=+0.000 m heading=+105.0 deg``."""
    x, y, theta = pose
    return f"x={x:+.3f} m y={y:+.3f} m heading={math.degrees(wrap_angle(theta)):+.1f} deg"


def sample_pose(sample: OdometrySample) -> Pose:
    """An odometry sample's pose (x m, y m, heading rad)."""
    return (sample.x_m, sample.y_m, sample.theta_rad)


@dataclass(frozen=True)
class StartPose:
    """Where the encoders read, against where the next trial starts.

    Attributes:
        trial: the trial about to run (or to be measured); 0 when none is.
        expected: where it starts, encoder frame (x m, y m, heading rad);
            None when there is nothing to compare (no attempt yet).
        actual: where the encoders read.
    """

    trial: int
    expected: Pose | None
    actual: Pose

    @property
    def distance_m(self) -> float:
        """How far the robot stands from the start, metres (0 when unknown)."""
        if self.expected is None:
            return 0.0
        return math.hypot(self.actual[0] - self.expected[0], self.actual[1] - self.expected[1])

    @property
    def heading_off_deg(self) -> float:
        """How far the robot is turned from the start heading, degrees, in (-180, 180]."""
        if self.expected is None:
            return 0.0
        return math.degrees(wrap_angle(self.actual[2] - self.expected[2]))

    @property
    def ok(self) -> bool:
        """Within :data:`POSITION_TOLERANCE_M` and :data:`HEADING_TOLERANCE_DEG`."""
        return (
            self.distance_m <= POSITION_TOLERANCE_M
            and abs(self.heading_off_deg) <= HEADING_TOLERANCE_DEG
        )

    def describe(self) -> str:
        """What the encoders read and where trial ``trial`` starts."""
        text = f"encoders {pose_text(self.actual)}"
        if self.expected is None:
            return text
        text += f"; trial {self.trial} starts at {pose_text(self.expected)}"
        if self.ok:
            return text
        return (
            f"{text}: the robot is {self.distance_m:.3f} m away and turned "
            f"{self.heading_off_deg:+.1f} deg (tolerance {POSITION_TOLERANCE_M:g} m, "
            f"{HEADING_TOLERANCE_DEG:g} deg)"
        )


def expected_start(state: SessionState) -> tuple[int, Pose] | None:
    """The next trial and where its encoders should read; None before any attempt
    or when the plan is done."""
    opened = state.open_trial
    if opened is not None:
        if opened.phase is Phase.MEASURING and opened.encoder_end_pose is not None:
            return opened.trial, tuple(opened.encoder_end_pose)  # type: ignore[return-value]
        return opened.trial, (0.0, 0.0, 0.0)
    trial = state.next_trial()
    if trial is None:
        return None
    if state.attempts.get(trial, 0) > 0:  # an attempt of it was voided: it started here
        return trial, (0.0, 0.0, 0.0)
    if not state.completed:
        return None
    last = state.completed[-1]
    return trial, tuple(last.encoder_end_pose)  # type: ignore[return-value]


def check_start(state: SessionState, sample: OdometrySample) -> StartPose:
    """Compare the encoders with where the next trial starts."""
    where = expected_start(state)
    if where is None:
        next_trial = state.next_trial()
        return StartPose(next_trial or 0, None, sample_pose(sample))
    trial, expected = where
    return StartPose(trial, expected, sample_pose(sample))


def refuse_off_start(start: StartPose) -> None:
    """For unattended runs: raise unless the robot is at the trial's start.

    Raises:
        SafetyError: names where the robot is, where the trial starts, and the
            way out (put it back, or ``--from-here``).
    """
    if start.ok:
        return
    raise SafetyError(
        f"the robot is not where trial {start.trial} starts: {start.describe()}. "
        "Put it back there and run the command again, or give --from-here to "
        "start the trial where it stands"
    )


def put_back(start: StartPose, reply: str, robot: Robot) -> str:
    """For the operator, asked to put the robot back at trial ``start.trial``'s
    start (``put_back_prompt``): ``reply`` ``here`` starts the trial where the
    robot stands; anything else means it was put back, so the encoders are set
    to the trial's start. What to tell the operator."""
    if reply.strip().lower() == HERE:
        return "The trial starts where the robot stands."
    assert start.expected is not None
    robot.zero(start.expected)
    return "Encoders set to the trial's start."
