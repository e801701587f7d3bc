"""Robot-neutral odometry values that every driver backend hands up.

A backend (odohil/driver/nomad/, odohil/driver/create2/, ...) converts its
wire units here, once, so nothing above the driver layer knows a robot's
units. The session layer's ``Robot`` protocol (odohil/session/robots/protocol.py) is
written in these types.
"""

from __future__ import annotations

from dataclasses import dataclass

from odohil.science.paths import Drivable


@dataclass(frozen=True)
class OdometrySample:
    """What the robot's own odometry said at one moment, in SI units.

    Attributes:
        host_time_s: host monotonic clock when the reading arrived, s.
        robot_time_s: the robot's own timestamp, s (the host time when the
            robot sends none).
        x_m, y_m: odometry position in the odometry frame, m.
        theta_rad: odometry heading in the odometry frame, rad in (-pi, pi].
        moving: whether the robot reports any axis or wheel in motion.
        wire: the backend's own view of the reading, for messages only
            (for example "x=12 y=0 (0.1 in) steer=3599 (0.1 deg)").
    """

    host_time_s: float
    robot_time_s: float
    x_m: float
    y_m: float
    theta_rad: float
    moving: bool
    wire: str = ""

    def pose_text(self) -> str:
        """Short human-readable pose, SI, with the backend's wire view."""
        text = f"x={self.x_m:.4f} m y={self.y_m:.4f} m theta={self.theta_rad:.4f} rad"
        return f"{self.wire}; {text}" if self.wire else text


@dataclass(frozen=True)
class DriveSettings:
    """How a backend drives each trial (robot-neutral; each backend maps
    these onto its own commands and refuses what it cannot do).

    Attributes:
        speed_m_s: translation speed, m/s.
        turn_rate_rad_s: in-place turning rate, rad/s.
        acceleration_m_s2: translation acceleration, m/s^2.
        turn_acceleration_rad_s2: turning acceleration, rad/s^2.
        step_timeout_s: longest wall time of one leg or turn, s: the cap of
            each step's own limit, derived from its length and the speeds
            (odohil/driver/step_limit.py).
        watchdog_s: the robot's own watchdog, s (0 leaves it off): it stops
            the robot when the host dies mid-motion, where the robot has one.
    """

    speed_m_s: float = 0.5
    turn_rate_rad_s: float = 0.7853981633974483
    acceleration_m_s2: float = 0.5
    turn_acceleration_rad_s2: float = 0.5235987755982988
    step_timeout_s: float = 120.0
    watchdog_s: float = 2.0


@dataclass(frozen=True)
class TrialMotion:
    """What one trial's motion did, as the robot's odometry saw it.

    Attributes:
        design: the trial driven: a forth-and-back design (one-way trials
            may be backward) or a general path design.
        samples: every odometry sample taken during the motion, in time order.
        start, end: samples before the first and after the last step.
        end_pose: ``end`` in the frame of ``start``: (x m, y m, heading
            change rad in (-pi, pi]).
        started_s, ended_s: host monotonic times of the motion, s.
    """

    design: Drivable
    samples: tuple[OdometrySample, ...]
    start: OdometrySample
    end: OdometrySample
    end_pose: tuple[float, float, float]
    started_s: float
    ended_s: float

    @property
    def duration_s(self) -> float:
        """Wall time of the motion, s."""
        return self.ended_s - self.started_s
