"""The seam between a session and what measures its trials (``--measure``).

``fake`` (the fake robot's true pose as a tape with simulated noise), a trial
file's path, ``tcp://HOST:PORT`` (a motion-capture stream) or ``operator``
(the wizard's person with a tape, whose source the wizard builds itself).
Moved here from odohil/cli/run.py as it was; the pose-source registry
replaces :func:`parse_measure`, :func:`check_measure`, :func:`open_stream`
and :func:`make_source` behind these four names.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

from odohil.errors import InitError, ParameterError
from odohil.science.robot_description import RobotDescription
from odohil.session.mocap import MotionCaptureSource, PoseStream, pose_sigma_of, require_pose
from odohil.session.pose_source import PoseSource
from odohil.session.sources import FakeTruthSource, TapeSource, TruthReader

MOCAP_SCHEME = "tcp://"
"""``--measure`` values starting so name a motion-capture stream."""
MOCAP_FIRST_POSE_S = 3.0
"""How long a motion-capture stream may take to deliver its first pose, s."""
OPERATOR = "operator"
"""The wizard's measurement: a person with a tape."""


@dataclass(frozen=True)
class MeasureOption:
    """What ``--measure`` names.

    Attributes:
        kind: ``fake``, ``file``, ``tcp`` or ``operator`` (as journaled in the header).
        trial_file: the trial file of ``file``.
        mocap_url: the stream of ``tcp``.
    """

    kind: str
    trial_file: str | None = None
    mocap_url: str | None = None


def parse_measure(measure: str) -> MeasureOption:
    """``--measure``: ``fake``, ``operator``, ``tcp://HOST:PORT`` or a trial file's path."""
    if measure in ("fake", OPERATOR):
        return MeasureOption(measure)
    if measure.startswith(MOCAP_SCHEME) or "://" in measure:
        return MeasureOption("tcp", mocap_url=measure)
    return MeasureOption("file", trial_file=measure)


def check_stream_url(option: MeasureOption, description: RobotDescription) -> None:
    """A motion-capture URL's form and the description's pose_sigma, checked
    before anything opens (ParameterError)."""
    if option.mocap_url is not None:
        PoseStream(option.mocap_url)
        pose_sigma_of(description, option.mocap_url)


class SnapshotTruth:
    """The fake robot's true pose through anything with a ``truth()`` snapshot."""

    def __init__(self, owner: Any) -> None:
        self.owner = owner

    def true_pose(self) -> tuple[float, float, float]:
        """True (x m, y m, heading rad)."""
        snapshot = self.owner.truth() if hasattr(self.owner, "truth") else self.owner.snapshot()
        return (snapshot.true_x_m, snapshot.true_y_m, snapshot.true_theta_rad)


@contextlib.contextmanager
def open_stream(url: str | None) -> Iterator[PoseStream | None]:
    """The motion-capture stream at ``url``, delivering a pose within
    :data:`MOCAP_FIRST_POSE_S` (InitError or MeasurementError: nothing moved).
    None when ``url`` is None. Closed on exit."""
    if url is None:
        yield None
        return
    stream = PoseStream(url)
    try:
        stream.open()
        require_pose(stream, MOCAP_FIRST_POSE_S)
    except BaseException:
        stream.close()
        raise
    with stream:
        yield stream


def make_source(
    option: MeasureOption,
    description: RobotDescription,
    truth: Any,
    seed: int,
    mocap: PoseStream | None = None,
) -> PoseSource | None:
    """The pose source ``option`` names: ``fake`` (the fake's truth as a tape
    with simulated noise, through the floor-marks solver), ``file`` (a trial
    file: poses read as poses, raw distances through the solver), ``tcp``
    (motion capture on the open ``mocap`` stream); None for ``operator``
    (the wizard builds it).

    Raises:
        InitError: ``fake`` without the fake's truth, ``tcp`` without a stream.
        ParameterError: an unknown kind.
    """
    if option.kind == OPERATOR:
        return None
    if option.kind == "tcp":
        if mocap is None:
            raise InitError(
                "the session measures by motion capture but names no stream: give "
                "--measure tcp://HOST:PORT"
            )
        return MotionCaptureSource(mocap, pose_sigma_of(description, mocap.url))
    if option.kind == "fake":
        if truth is None:
            raise InitError(
                "--measure fake needs the fake robot's truth side channel: give "
                "--truth-socket PATH (the path `odohil emulate` printed) or the fake's own URL "
                "(fakerobot://, fakecreate2://)"
            )
        reader: TruthReader = SnapshotTruth(truth)
        return TapeSource(FakeTruthSource(reader, description, seed=seed), description)
    if option.kind == "file" and option.trial_file:
        from odohil.session.sources import pose_source_from_file

        return pose_source_from_file(option.trial_file, description)
    raise ParameterError(f"unknown measurement source {option.kind!r}")
