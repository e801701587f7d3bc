"""The ``Robot`` protocol: everything the session needs from a robot.

The session owns this protocol and names no robot: a backend in the driver
layer (odohil/driver/<name>/) implements it structurally and is found by the
robot description's ``[robot] protocol`` name through the ``odohil.robots``
entry-point group (odohil/session/robots/registry.py), the way python-can finds a bus
by its interface name. Values crossing it are robot-neutral and SI
(odohil/driver/odometry.py).
"""

from __future__ import annotations

from collections.abc import Callable
from types import TracebackType
from typing import Protocol, Self

from odohil.driver.odometry import DriveSettings, OdometrySample, TrialMotion
from odohil.science.paths import Drivable

SampleCallback = Callable[[OdometrySample], None]
"""Called with every odometry sample taken during a motion (live read-outs)."""


class Robot(Protocol):
    """A connected robot. Closing it (``close`` or leaving the ``with``
    block) stops it, best effort, before the port closes."""

    @property
    def port(self) -> str:
        """The port URL it is connected through."""
        ...

    @property
    def transport(self) -> object:
        """The open pyserial port it talks through (a backend's in-process
        fake port carries the fake's true pose: ``truth()``)."""
        ...

    def __enter__(self) -> Self: ...

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None: ...

    def odometry(self) -> OdometrySample:
        """Read the odometry now (also feeds the robot's watchdog)."""
        ...

    def arm(self, settings: DriveSettings) -> OdometrySample:
        """Prepare to drive trials (mode, watchdog, speeds); the odometry after."""
        ...

    def settle(self, timeout_s: float) -> OdometrySample:
        """Bring the robot to rest (stop it if it moves), within ``timeout_s``."""
        ...

    def zero(self, pose: tuple[float, float, float] = (0.0, 0.0, 0.0)) -> OdometrySample:
        """Make the odometry read ``pose`` (x m, y m, heading rad) where the
        robot stands: the origin by default (before each trial), or a trial's
        start pose (the wizard, once the robot is put back); the reading after."""
        ...

    def drive(
        self,
        design: Drivable,
        settings: DriveSettings,
        on_sample: SampleCallback | None = None,
    ) -> TrialMotion:
        """Drive one trial of ``design`` (a forth-and-back design or a general
        path: its encoder path's legs and turns), checking every step against the
        odometry, each within its own time limit; stops the robot before raising
        on any failure and resends nothing. Every step is checked before the
        first is sent: ParameterError naming the step (``turn 0.1 rad (step 2
        of 8)``) and the backend's accepted range, nothing moved."""
        ...

    def stop(self) -> None:
        """Command a stop now, without waiting."""
        ...

    def stop_and_confirm(self, timeout_s: float) -> OdometrySample:
        """Stop and wait until the robot reports standing still; raises
        StopUnconfirmedError when it does not within ``timeout_s``."""
        ...

    def close(self) -> None:
        """Stop (best effort) and close the port. Idempotent."""
        ...
