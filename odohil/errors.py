"""The one exception hierarchy of odohil.

Every error odohil raises on purpose is an :class:`OdohilError`, in one of five
branches, so callers can catch exactly what they can handle:

- :class:`InitError`: bad configuration or set-up (parameters, robot description,
  a port that does not open, a robot that does not answer when connecting);
- :class:`ProtocolError`: bytes on the wire that break the Nomad protocol
  (framing, checksum, NAK, a reply of the wrong type);
- :class:`OdohilTimeoutError`: the robot did not answer, or did not finish a
  motion, within the allowed time (float seconds);
- :class:`MeasurementError`: floor-mark distances or trial data that cannot be
  used (not a number, negative, no rigid motion explains them, bad file rows);
- :class:`SafetyError`: the robot is not known to be safe (its stop could not
  be confirmed, or it is not where the next motion must start).

:class:`MotionError` (a motion that did not end where the encoders say it
should) sits under :class:`OdohilError` directly.
"""

from __future__ import annotations


class OdohilError(Exception):
    """Base class of every error odohil raises on purpose."""


class InitError(OdohilError):
    """Configuration or set-up is wrong: fix the input and start again."""


class ParameterError(InitError, ValueError):
    """A numeric argument is out of its domain (for example a negative length)."""


class PortOptionError(ParameterError):
    """A port URL with an option its transport does not accept (an unknown
    option, a value of the wrong kind): bad input, refused before anything is
    sent. A pyserial URL handler raises it from ``open``, and pyserial passes
    it through ``serial_for_url`` (it is a ValueError); odohil/driver/port.py
    keeps it, naming the URL."""


class RobotDescriptionError(InitError):
    """The robot description (TOML) is invalid."""


class ConnectionFailedError(InitError):
    """The port does not open, or the robot does not answer at connect time."""


class ProtocolError(OdohilError):
    """The bytes on the wire break the Nomad protocol."""


class FramingError(ProtocolError):
    """Bad start byte, absurd length or bad end byte."""


class ChecksumError(ProtocolError):
    """The checksum byte does not match the packet."""


class NakError(ProtocolError):
    """The robot answered NAK (type 8)."""


class UnexpectedReplyError(ProtocolError):
    """A well-formed reply of a type or size that does not answer the request."""


class DisconnectedError(ProtocolError):
    """The serial line went away (port closed, EIO on a pseudo-terminal)."""


class OdohilTimeoutError(OdohilError, TimeoutError):
    """No (complete) reply, or no end of motion, within the timeout."""


class MotionError(OdohilError):
    """A motion ended somewhere other than where the encoders say it should."""


class MeasurementError(OdohilError, ValueError):
    """Measurements or trial data that cannot be used as they are."""


class InconsistentMeasurementError(MeasurementError):
    """Distances that no rigid motion explains within the measurement error.

    Attributes:
        labels: the distances the rejection names (the suspect first, then any
            whose removal would do about as well); empty when it names none.
    """

    def __init__(self, message: str, labels: tuple[str, ...] = ()) -> None:
        super().__init__(message)
        self.labels = labels


class TrialFileError(MeasurementError):
    """A trial file with bad rows; the message lists each by line number."""


class RecordingError(MeasurementError):
    """A recorded log (odometry and ground truth) that cannot be read or cut
    into trials; the message names the file, the line or message, and the field."""


class JournalError(OdohilError):
    """A session journal that cannot be trusted: unreadable, or corrupt before
    its last record (a torn last record is reported, not raised)."""


class SafetyError(OdohilError):
    """The robot is not known to be safe to leave or to move."""


class StopUnconfirmedError(SafetyError):
    """A stop was sent but the robot did not report standing still: it may still be moving."""


class SafetyStopError(SafetyError):
    """The robot reported a hazard (cliff, wheel drop, bump) or left the mode it
    drives in (a drop to Passive) during a motion: it was told to stop and the
    trial ends."""
