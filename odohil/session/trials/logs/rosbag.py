"""ROS 2 bags (sqlite3 or MCAP storage) through the ``rosbags`` library.

``rosbags`` reads (and writes) both storage formats in pure Python, without a
ROS installation, so a log recorded on the robot with ``ros2 bag record`` is
read on any machine. Two topics are used, named by option:

- ``--odom-topic`` (default ``/odom``): nav_msgs/msg/Odometry, the robot's
  own odometry (``pose.pose``);
- ``--truth-topic`` (default ``/ground_truth``): geometry_msgs/msg/PoseStamped
  (``pose``) or nav_msgs/msg/Odometry (``pose.pose``), e.g. from a motion
  capture driver.

Times are the messages' ``header.stamp`` (the time the pose refers to, not
when it was written to the bag). A planar pose is (x, y) and the heading
about z of the orientation quaternion. The two topics are associated as the
evo tool does (:func:`odohil.session.trials.logs.recording.associate`) and the
recording is cut at rest. A path is a bag folder (with ``metadata.yaml``) or
a single ``.mcap``/``.db3`` file of one.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from odohil.errors import RecordingError
from odohil.science.robot_description import RobotDescription
from odohil.session.trials.logs.files import MAX_BAG_BYTES, check_regular
from odohil.session.trials.logs.recording import (
    ImportOptions,
    associate,
    check_increasing,
)
from odohil.session.trials.logs.tum import QUATERNION_TOLERANCE, heading_of
from odohil.session.trials.logs.windows import Cut, cut_of, joined, next_number

ODOMETRY_TYPE = "nav_msgs/msg/Odometry"
TRUTH_TYPES = ("geometry_msgs/msg/PoseStamped", ODOMETRY_TYPE)
MAX_MESSAGES = 5_000_000
"""Most messages read from one topic."""


def _bag_files(path: Path) -> Path:
    """The bag to open: a folder (its storage files' sizes checked) or a file."""
    if path.is_dir():
        if not (path / "metadata.yaml").is_file():
            raise RecordingError(f"{path}: not a ROS 2 bag folder (no metadata.yaml)")
        for storage in sorted(path.iterdir()):
            if storage.suffix in (".mcap", ".db3"):
                check_regular(storage, MAX_BAG_BYTES)
        return path
    check_regular(path, MAX_BAG_BYTES)
    if path.suffix not in (".mcap", ".db3"):
        raise RecordingError(f"{path}: not a ROS 2 bag (a folder, or a .mcap or .db3 file)")
    return path


def _pose(message: Any, msgtype: str) -> tuple[float, float, float]:
    pose = message.pose.pose if msgtype == ODOMETRY_TYPE else message.pose
    q = pose.orientation
    norm = math.sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w)
    if abs(norm - 1.0) > QUATERNION_TOLERANCE:
        raise ValueError(f"orientation: not a unit quaternion (norm {norm:.6g})")
    values = (float(pose.position.x), float(pose.position.y), heading_of(q.x, q.y, q.z, q.w))
    if not all(math.isfinite(v) for v in values):
        raise ValueError("position: not finite")
    return values


def read_topics(
    path: Path, odom_topic: str, truth_topic: str
) -> dict[str, tuple[list[float], list[tuple[float, float, float]], list[int]]]:
    """Stamps (s), planar poses and message numbers (1-based, per topic) of
    the two topics of one bag.

    Raises:
        RecordingError: not a bag, a topic missing or of the wrong type (the
            message lists the bag's topics), a message that does not decode.
    """
    from rosbags.highlevel import AnyReader, AnyReaderError
    from rosbags.typesys import Stores, get_typestore

    bag = _bag_files(path)
    found: dict[str, tuple[list[float], list[tuple[float, float, float]], list[int]]] = {
        odom_topic: ([], [], []),
        truth_topic: ([], [], []),
    }
    try:
        with AnyReader([bag], default_typestore=get_typestore(Stores.ROS2_HUMBLE)) as reader:
            topics = {c.topic: c.msgtype for c in reader.connections}
            listed = ", ".join(f"{t} ({m})" for t, m in sorted(topics.items())) or "none"
            for topic, allowed, option in (
                (odom_topic, (ODOMETRY_TYPE,), "--odom-topic"),
                (truth_topic, TRUTH_TYPES, "--truth-topic"),
            ):
                if topic not in topics:
                    raise RecordingError(
                        f"{path}: {option}: no topic {topic!r} in the bag; its topics: {listed}"
                    )
                if topics[topic] not in allowed:
                    raise RecordingError(
                        f"{path}: {option}: topic {topic!r} is {topics[topic]}; "
                        f"expected {' or '.join(allowed)}"
                    )
            connections = [c for c in reader.connections if c.topic in found]
            for connection, _, raw in reader.messages(connections=connections):
                stamps, poses, numbers = found[connection.topic]
                number = len(numbers) + 1
                try:
                    message: Any = reader.deserialize(raw, connection.msgtype)
                    stamp = message.header.stamp
                    stamps.append(float(stamp.sec) + 1e-9 * float(stamp.nanosec))
                    poses.append(_pose(message, connection.msgtype))
                except (ValueError, AttributeError, KeyError, IndexError) as exc:
                    raise RecordingError(
                        f"{path} message {number} of {connection.topic}: {exc}"
                    ) from None
                numbers.append(number)
                if number > MAX_MESSAGES:
                    raise RecordingError(
                        f"{path}: {connection.topic}: more than {MAX_MESSAGES} messages"
                    )
    except AnyReaderError as exc:
        raise RecordingError(f"{path}: cannot read the bag: {exc}") from None
    for topic, (stamps, _, _) in found.items():
        if not stamps:
            raise RecordingError(f"{path}: topic {topic!r} holds no message; no trial in the log")
    return found


def read_bags(paths: list[Path], description: RobotDescription, options: ImportOptions) -> Cut:
    """The trials of ROS 2 bags, numbered from 1 in bag order."""
    cuts: list[Cut] = []
    for path in paths:
        topics = read_topics(path, options.odom_topic, options.truth_topic)
        arrays = {}
        for topic, (stamps, poses, numbers) in topics.items():
            t = np.array(stamps, dtype=np.float64)
            where = np.array(numbers, dtype=np.int64)
            # header stamps, in the order the bag holds them
            check_increasing(t, where, f"{path} {topic}", "header.stamp", "message")
            arrays[topic] = (t, np.array(poses, dtype=np.float64), where)
        t_odo, odo, odo_where = arrays[options.odom_topic]
        t_truth, truth, _ = arrays[options.truth_topic]
        recording = associate(
            str(path),
            t_odo,
            odo,
            odo_where,
            t_truth,
            truth,
            options,
            unit="message",
            odometry_field=f"{options.odom_topic} pose",
            truth_field=f"{options.truth_topic} pose",
        )
        cuts.append(cut_of(recording, description, options, next_number(cuts)))
    return joined(cuts)
