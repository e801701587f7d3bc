"""``NomadBackend``: a Nomad 150 behind the session's ``Robot`` protocol.

Registered as ``nomad150`` in the ``odohil.robots`` entry-point group
(pyproject.toml). It wraps a :class:`~odohil.driver.nomad.robot.NomadRobot`
and converts each encoder sample (wire units, steering in [0, 2 pi)) to the
robot-neutral :class:`~odohil.driver.odometry.OdometrySample` here, once.
"""

from __future__ import annotations

from collections.abc import Callable
from types import TracebackType

from odohil.driver import stopping
from odohil.driver.guardian import Guardian, start_guardian
from odohil.driver.nomad.facts import NOMAD150_FACTS
from odohil.driver.nomad.link import open_port
from odohil.driver.nomad.motion import DEFAULT_TOLERANCE_WIRE, MotionRecord, drive_trial
from odohil.driver.nomad.robot import NomadRobot
from odohil.driver.nomad.sample import EncoderSample
from odohil.driver.odometry import DriveSettings, OdometrySample, TrialMotion
from odohil.driver.port import Port
from odohil.errors import ParameterError
from odohil.protocol.nomad import messages as m
from odohil.science.paths import Drivable
from odohil.units import wrap_angle

SampleCallback = Callable[[OdometrySample], None]


def odometry_sample(sample: EncoderSample) -> OdometrySample:
    """An encoder sample in robot-neutral SI units (heading wrapped to (-pi, pi])."""
    return OdometrySample(
        host_time_s=sample.host_time_s,
        robot_time_s=sample.robot_time_s,
        x_m=sample.x_m,
        y_m=sample.y_m,
        theta_rad=wrap_angle(sample.steer_rad),
        moving=sample.moving,
        wire=(
            f"x={sample.x_wire} y={sample.y_wire} (0.1 in) steer={sample.steer_wire} "
            f"turret={sample.turret_wire} (0.1 deg)"
        ),
    )


def trial_motion(record: MotionRecord) -> TrialMotion:
    """A forth-and-back record in robot-neutral units."""
    return TrialMotion(
        design=record.design,
        samples=tuple(odometry_sample(s) for s in record.samples),
        start=odometry_sample(record.start),
        end=odometry_sample(record.end),
        end_pose=record.end_pose,
        started_s=record.started_s,
        ended_s=record.ended_s,
    )


class NomadBackend:
    """A connected Nomad 150 as the session's ``Robot`` (context manager;
    closing it sends ``st``).

    Args:
        robot: the connected Nomad.
        port: the URL it was opened on.
        transport: the open pyserial port (a fake's carries its truth channel).
        tolerance_wire: how far (0.1 in / 0.1 deg) a step may end off its command.
    """

    facts = NOMAD150_FACTS
    name = NOMAD150_FACTS.name
    default_baud = NOMAD150_FACTS.default_baud

    def __init__(
        self,
        robot: NomadRobot,
        port: str = "",
        transport: object = None,
        tolerance_wire: int = DEFAULT_TOLERANCE_WIRE,
    ) -> None:
        self.nomad = robot
        self._port = port
        self.transport = transport
        self.tolerance_wire = tolerance_wire
        self.guardian: Guardian | None = None
        """Sends ``st`` if this process dies between :meth:`arm` and :meth:`close`."""

    @classmethod
    def open(
        cls,
        url: str,
        baud: int | None = None,
        robot: object = None,
        *,
        reply_timeout_s: float | None = None,
    ) -> NomadBackend:
        """Open ``url`` at ``baud`` (the Nomad's default when None) and check
        that the robot answers ``gs``. ``robot`` (the description's ``[robot]``
        settings) is accepted and ignored: a synchronous drive needs no
        kinematic constants here. ``reply_timeout_s``: the first-byte wait of
        ordinary requests and the silence that aborts a reply, s (None: 1 s,
        ``NORMAL_TIMEOUT_S``; the description's ``[serial] timeout_s``).

        Raises ParameterError for an unsupported baud, ConnectionFailedError
        when the port does not open or the robot does not answer.
        """
        if reply_timeout_s is not None:
            NOMAD150_FACTS.check_reply_timeout(reply_timeout_s)
        raw = open_port(url, cls.default_baud if baud is None else baud)
        return cls.from_port(raw, url, reply_timeout_s)

    @classmethod
    def from_port(
        cls, raw: Port, url: str = "", reply_timeout_s: float | None = None
    ) -> NomadBackend:
        """Wrap an already open port and check that the robot answers ``gs``."""
        name = url or str(getattr(raw, "name", "") or getattr(raw, "port", "") or "")
        return cls(NomadRobot.from_port(raw, name, reply_timeout_s), name, raw)

    @property
    def port(self) -> str:
        """The port URL it is connected through."""
        return self._port

    def __enter__(self) -> NomadBackend:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()

    def odometry(self) -> OdometrySample:
        """One ``gs``: the encoders now (also feeds the watchdog)."""
        return odometry_sample(self.nomad.state())

    def arm(self, settings: DriveSettings) -> OdometrySample:
        """Start the guardian (odohil/driver/guardian.py: ``st`` if this process
        dies), set the watchdog (``conf_tm``) when ``settings.watchdog_s`` > 0;
        the encoders after. Speeds and accelerations are sent before each trial."""
        if self.guardian is None:
            self.guardian = start_guardian(self.transport, m.encode_request(m.St()))
        if settings.watchdog_s > 0:
            self.nomad.set_watchdog(settings.watchdog_s)
        return self.odometry()

    def settle(self, timeout_s: float) -> OdometrySample:
        """Stop the robot if it moves and wait (``gs`` polls) until it stands
        still (odohil/driver/stopping.py ``settle``)."""
        return stopping.settle(
            timeout_s,
            read=self.odometry,
            moving=lambda sample: sample.moving,
            confirm=self.stop_and_confirm,
        )

    def zero(self, pose: tuple[float, float, float] = (0.0, 0.0, 0.0)) -> OdometrySample:
        """``dp`` and ``da``: the encoders read ``pose`` (x m, y m, heading rad) here."""
        x_m, y_m, theta_rad = pose
        self.nomad.define_pose(x_m, y_m)
        self.nomad.define_angles(theta_rad, 0.0)
        return self.odometry()

    def drive(
        self,
        design: Drivable,
        settings: DriveSettings,
        on_sample: SampleCallback | None = None,
    ) -> TrialMotion:
        """One trial, forth-and-back or a general path
        (:func:`~odohil.driver.nomad.motion.drive_trial`); ``on_sample`` sees every
        encoder sample as an OdometrySample."""
        if settings.step_timeout_s <= 0:
            raise ParameterError(f"step timeout must be > 0 s, got {settings.step_timeout_s!r}")
        hook = None
        if on_sample is not None:
            callback = on_sample

            def hook(sample: EncoderSample) -> None:
                callback(odometry_sample(sample))

        record = drive_trial(
            self.nomad,
            design,
            tolerance_wire=self.tolerance_wire,
            step_timeout_s=settings.step_timeout_s,
            speeds=(settings.speed_m_s, settings.turn_rate_rad_s),
            accelerations=(settings.acceleration_m_s2, settings.turn_acceleration_rad_s2),
            on_sample=hook,
        )
        return trial_motion(record)

    def stop(self) -> None:
        """``st`` now."""
        self.nomad.stop()

    def stop_and_confirm(self, timeout_s: float) -> OdometrySample:
        """``st``, then ``gs`` until the robot reports standing still (see
        :meth:`NomadRobot.stop_and_confirm`)."""
        return odometry_sample(self.nomad.stop_and_confirm(timeout_s))

    def close(self) -> None:
        """``st`` (best effort), close the port, release the guardian. Idempotent.
        If the close itself fails, the guardian stays: it stops the robot when
        this process ends."""
        self.nomad.close()
        if self.guardian is not None:
            self.guardian.release()
