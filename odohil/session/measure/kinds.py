"""The built-in pose sources of ``--measure`` (odohil/session/measure/registry.py):
``fake`` (the fake robot's true pose measured as a tape), a trial file, and
``tcp://HOST:PORT`` (motion capture). Each is registered in pyproject.toml's
``odohil.pose_sources`` group and is always there besides.
"""

from __future__ import annotations

import contextlib
import re
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from odohil.errors import InitError, MeasurementError, ParameterError
from odohil.science.floor_marks import pose_covariance
from odohil.science.paths import FloatArray
from odohil.science.robot_description import RobotDescription
from odohil.session.addresses import parse_tcp_url
from odohil.session.measure.files import pose_source_from_file
from odohil.session.measure.mocap import (
    MotionCaptureSource,
    PoseStream,
    pose_sigma_of,
    require_pose,
    still_criteria_of,
)
from odohil.session.measure.mocap.change import pose_change_with_covariance
from odohil.session.measure.protocol import PoseSource
from odohil.session.measure.registry import (
    OPERATOR_WORDS,
    Connection,
    OpenContext,
    OpenedSource,
    Preflight,
    parse_measure,
)
from odohil.session.measure.tape.distances import FakeTruthSource
from odohil.session.measure.tape.source import TapeSource
from odohil.session.trials.pose_file import check_trial_file

__all__ = [
    "TrialFileSettings",
    "expected_pose_cov",
]

MOCAP_SCHEME = "tcp://"
"""``--measure`` values starting so name a motion-capture stream."""
MOCAP_FIRST_POSE_S = 3.0
"""How long a motion-capture stream may take to deliver its first pose, s."""

_SCHEME = re.compile(r"[A-Za-z][A-Za-z0-9+.-]+:")
"""A ``--measure`` text starting so names a kind by its scheme (``tcp:``,
``toy:``), not a trial file (unless such a file exists)."""


def journaled_text(journaled: Mapping[str, Any], key: str, form: str) -> str:
    """The header's ``settings[key]`` (non-empty text).

    Raises:
        ParameterError: it is missing (the message names ``--measure`` and ``form``).
    """
    value = journaled.get(key)
    if not isinstance(value, str) or not value:
        raise ParameterError(
            f"the session's journal names no {key} for its measurement: give --measure {form}"
        )
    return value


class SnapshotTruth:
    """The fake robot's true pose through anything with a ``truth()`` snapshot
    (the in-process fake's port) or a ``snapshot()`` (a truth socket's client)."""

    def __init__(self, owner: Any) -> None:
        self.owner = owner

    def true_pose(self) -> tuple[float, float, float]:
        """True (x m, y m, heading rad)."""
        snapshot = self.owner.truth() if hasattr(self.owner, "truth") else self.owner.snapshot()
        return (snapshot.true_x_m, snapshot.true_y_m, snapshot.true_theta_rad)


@dataclass(frozen=True)
class FakeTruthSettings:
    """``--measure fake``: nothing to set (the seed is the session's)."""


NO_TRUTH = (
    "--measure fake needs the fake robot's truth side channel: give "
    "--truth-socket PATH (the path `odohil emulate` printed) or the fake's own URL "
    "(fakerobot://, fakecreate2://)"
)


class FakeTruthKind:
    """``fake``: the fake robot's true pose as a tape with simulated noise,
    through the floor-marks solver (:class:`FakeTruthSource`, :class:`TapeSource`)."""

    name = "fake"
    forms = "`fake` (the fake robot's true pose, measured as a tape with simulated noise)"
    floor_marks = True

    def parse(self, text: str) -> FakeTruthSettings | None:
        """``fake``."""
        return FakeTruthSettings() if text == "fake" else None

    def journal_settings(self, settings: FakeTruthSettings) -> dict[str, Any]:
        """Nothing beyond the session's seed and truth socket."""
        return {}

    def from_journal(self, journaled: Mapping[str, Any]) -> FakeTruthSettings:
        """Nothing to read back."""
        return FakeTruthSettings()

    def check(self, settings: FakeTruthSettings, preflight: Preflight) -> None:
        """The fake's true pose must be readable.

        Raises:
            ParameterError: no truth socket and no in-process fake port.
        """
        if not preflight.truth_available:
            raise ParameterError(NO_TRUTH)

    @contextlib.contextmanager
    def open(self, settings: FakeTruthSettings, ctx: OpenContext) -> Iterator[OpenedSource]:
        """Nothing to open before the robot; the source reads its truth channel."""

        def make(connection: Connection) -> PoseSource:
            if connection.truth is None:
                raise InitError(NO_TRUTH)
            tape = FakeTruthSource(SnapshotTruth(connection.truth), ctx.description, seed=ctx.seed)
            return TapeSource(tape, ctx.description)

        yield OpenedSource(make)


@dataclass(frozen=True)
class TrialFileSettings:
    """``--measure PATH``: a trial file (poses, or raw tape distances).

    Attributes:
        path: the file as given.
    """

    path: str


class TrialFileKind:
    """``file``: a trial file; poses read as poses, raw distances through the
    floor-marks solver (:func:`pose_source_from_file`). Asked last: it takes
    any text that names no other kind's scheme, or an existing file."""

    name = "file"
    forms = "a trial file's path (CSV of poses or tape distances, one row per trial)"
    floor_marks = True
    fallback = True

    def parse(self, text: str) -> TrialFileSettings | None:
        """Any text without a ``scheme:`` prefix, or an existing file; not a
        word for the operator's tape (:data:`OPERATOR_WORDS`) that names no file."""
        if (_SCHEME.match(text) or text.lower() in OPERATOR_WORDS) and not Path(text).exists():
            return None
        return TrialFileSettings(text)

    def journal_settings(self, settings: TrialFileSettings) -> dict[str, Any]:
        """``trial_file``: the file's absolute path."""
        return {"trial_file": str(Path(settings.path).resolve())}

    def from_journal(self, journaled: Mapping[str, Any]) -> TrialFileSettings:
        """The journaled ``trial_file``.

        Raises:
            ParameterError: the header names none.
        """
        return TrialFileSettings(journaled_text(journaled, "trial_file", "PATH (a trial file)"))

    def check(self, settings: TrialFileSettings, preflight: Preflight) -> None:
        """The file serves the plan (odohil/session/trials/pose_file.py ``check_trial_file``)."""
        check_trial_file(settings.path, preflight.description, preflight.plan)

    @contextlib.contextmanager
    def open(self, settings: TrialFileSettings, ctx: OpenContext) -> Iterator[OpenedSource]:
        """The file is read once the robot is connected."""
        yield OpenedSource(lambda connection: pose_source_from_file(settings.path, ctx.description))


@dataclass(frozen=True)
class MotionCaptureSettings:
    """``--measure tcp://HOST:PORT``.

    Attributes:
        url: the stream's URL.
    """

    url: str


class MotionCaptureKind:
    """``tcp``: still poses of a motion-capture stream (docs/motion-capture.md)."""

    name = "tcp"
    forms = "tcp://HOST:PORT (a motion-capture stream, docs/motion-capture.md)"
    floor_marks = False

    def parse(self, text: str) -> MotionCaptureSettings | None:
        """``tcp://...`` (its form is checked by :meth:`check`)."""
        return MotionCaptureSettings(text) if text.startswith(MOCAP_SCHEME) else None

    def journal_settings(self, settings: MotionCaptureSettings) -> dict[str, Any]:
        """``mocap_url``."""
        return {"mocap_url": settings.url}

    def from_journal(self, journaled: Mapping[str, Any]) -> MotionCaptureSettings:
        """The journaled ``mocap_url``.

        Raises:
            ParameterError: the header names none.
        """
        return MotionCaptureSettings(journaled_text(journaled, "mocap_url", "tcp://HOST:PORT"))

    def check(self, settings: MotionCaptureSettings, preflight: Preflight) -> None:
        """The URL's form and the description's pose_sigma (nothing connects).

        Raises:
            ParameterError: not ``tcp://HOST:PORT``.
            RobotDescriptionError: no ``[measurement] pose_sigma``.
        """
        parse_tcp_url(settings.url)
        pose_sigma_of(preflight.description, settings.url)

    @contextlib.contextmanager
    def open(self, settings: MotionCaptureSettings, ctx: OpenContext) -> Iterator[OpenedSource]:
        """Connect to the stream and require a pose within
        :data:`MOCAP_FIRST_POSE_S`; closed on exit.

        Raises:
            InitError: nobody at the URL, or no pose in time (nothing moved).
        """
        url = settings.url
        sigma = pose_sigma_of(ctx.description, url)
        criteria = still_criteria_of(ctx.description)
        stream = PoseStream(url)
        try:
            stream.open()
            require_pose(stream, MOCAP_FIRST_POSE_S)
        except (InitError, MeasurementError) as exc:
            stream.close()
            raise InitError(f"{exc}; nothing moved") from None
        try:
            yield OpenedSource(
                lambda connection: MotionCaptureSource(stream, sigma, criteria),
                note=f"motion capture {url}: poses arriving",
            )
        finally:
            stream.close()


FAKE = FakeTruthKind()
TRIAL_FILE = TrialFileKind()
MOTION_CAPTURE = MotionCaptureKind()
BUILTIN_KINDS = (FAKE, TRIAL_FILE, MOTION_CAPTURE)
"""The pose sources odohil brings."""


def expected_pose_cov(
    measure: str | None, description: RobotDescription, pose_change: FloatArray
) -> FloatArray:
    """The covariance a measured pose change near ``pose_change`` (x m, y m,
    rad) will carry with ``--measure`` (before anything is measured: a
    validation's sizing, odohil/session/commands/validate_power.py): a
    motion-capture stream's two still poses with the description's
    ``pose_sigma``; else the tape's floor-mark solver (``fake``, the operator,
    a trial file of distances).

    Raises:
        ParameterError: a malformed ``--measure``.
        RobotDescriptionError: motion capture without ``pose_sigma``.
    """
    settings = None if measure is None else parse_measure(measure).settings
    if isinstance(settings, MotionCaptureSettings):
        cov = np.diag(np.square(pose_sigma_of(description, settings.url)))
        _, change = pose_change_with_covariance((0.0, 0.0, 0.0), pose_change.tolist(), cov, cov)
        return change
    return pose_covariance(description, pose_change)
