"""ROS 2 bags (odohil/session/trials/logs/rosbag.py), written by the rosbags
library itself in both storage formats (sqlite3 and MCAP)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore

from odohil.errors import RecordingError
from odohil.session.trials.logs import ImportOptions, guess_format, read_recording
from tests.logs.data import optiodom_robot
from tests.logs.synth import SynthLog, synth_log, varied_motions

STORE = get_typestore(Stores.ROS2_HUMBLE)
T = STORE.types


def _stamp(t: float) -> Any:
    sec = math.floor(t)
    return T["builtin_interfaces/msg/Time"](sec=sec, nanosec=round((t - sec) * 1e9))


def _pose(x: float, y: float, theta: float) -> Any:
    return T["geometry_msgs/msg/Pose"](
        position=T["geometry_msgs/msg/Point"](x=x, y=y, z=0.0),
        orientation=T["geometry_msgs/msg/Quaternion"](
            x=0.0, y=0.0, z=math.sin(theta / 2), w=math.cos(theta / 2)
        ),
    )


def _odometry(t: float, pose: np.ndarray) -> Any:
    zero = T["geometry_msgs/msg/Vector3"](x=0.0, y=0.0, z=0.0)
    return T["nav_msgs/msg/Odometry"](
        header=T["std_msgs/msg/Header"](stamp=_stamp(t), frame_id="odom"),
        child_frame_id="base_link",
        pose=T["geometry_msgs/msg/PoseWithCovariance"](pose=_pose(*pose), covariance=np.zeros(36)),
        twist=T["geometry_msgs/msg/TwistWithCovariance"](
            twist=T["geometry_msgs/msg/Twist"](linear=zero, angular=zero), covariance=np.zeros(36)
        ),
    )


def _pose_stamped(t: float, pose: np.ndarray) -> Any:
    return T["geometry_msgs/msg/PoseStamped"](
        header=T["std_msgs/msg/Header"](stamp=_stamp(t), frame_id="world"), pose=_pose(*pose)
    )


def write_bag(
    path: Path,
    log: SynthLog,
    storage: StoragePlugin,
    *,
    truth_type: str = "geometry_msgs/msg/PoseStamped",
    truth_topic: str = "/mocap/robot/pose",
) -> Path:
    """A bag as ``ros2 bag record`` would hold it: odometry at 50 Hz, the capture at 25 Hz."""
    with Writer(path, version=9, storage_plugin=storage) as writer:
        odom = writer.add_connection("/odom", "nav_msgs/msg/Odometry", typestore=STORE)
        truth = writer.add_connection(truth_topic, truth_type, typestore=STORE)
        make = _odometry if truth_type == "nav_msgs/msg/Odometry" else _pose_stamped
        for index, t in enumerate(log.t_s):
            received = round((t + 0.004) * 1e9)  # written a little after the stamp
            writer.write(
                odom,
                received,
                STORE.serialize_cdr(_odometry(t, log.odometry[index]), "nav_msgs/msg/Odometry"),
            )
            if index % 2 == 0:
                message = make(t + 0.002, log.truth[index])
                writer.write(truth, received + 1, STORE.serialize_cdr(message, truth_type))
    return path


@pytest.mark.parametrize("storage", [StoragePlugin.SQLITE3, StoragePlugin.MCAP])
def test_a_bag_of_either_storage_gives_the_motions(tmp_path: Path, storage: StoragePlugin) -> None:
    log = synth_log(varied_motions())
    bag = write_bag(tmp_path / "run", log, storage)
    assert guess_format([bag]) == "rosbag"
    options = ImportOptions(format="rosbag", truth_topic="/mocap/robot/pose")
    trials = read_recording([bag], optiodom_robot(), options)
    assert [(t.family, t.direction) for t in trials] == [
        ("straight", "forward"),
        ("spin", "cw"),
        ("straight", "backward"),
        ("arc", "ccw"),
    ]
    for trial, true in zip(trials, log.true_changes, strict=True):
        expected = np.array(true) - [0.0, 0.0, trial.path.winding_rad]
        sd = np.sqrt(np.diag(trial.measurement_cov))
        assert np.all(np.abs(trial.pose_change - expected) < 5 * sd + 1e-9)
        assert trial.source == str(bag)


def test_the_ground_truth_may_be_odometry_messages_in_a_single_mcap_file(tmp_path: Path) -> None:
    log = synth_log(varied_motions()[:3])
    bag = write_bag(
        tmp_path / "run",
        log,
        StoragePlugin.MCAP,
        truth_type="nav_msgs/msg/Odometry",
        truth_topic="/ground_truth",
    )
    (single,) = sorted(bag.glob("*.mcap"))
    (trial,) = read_recording([single], optiodom_robot(), ImportOptions(format="rosbag"))
    assert trial.family == "straight"


def test_a_missing_topic_lists_the_bags_topics(tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "run", synth_log(varied_motions()[:3]), StoragePlugin.SQLITE3)
    with pytest.raises(
        RecordingError,
        match=r"run: --truth-topic: no topic '/ground_truth' in the bag; its topics: "
        r"/mocap/robot/pose \(geometry_msgs/msg/PoseStamped\), /odom",
    ):
        read_recording([bag], optiodom_robot(), ImportOptions(format="rosbag"))


def test_a_topic_of_the_wrong_type_is_refused(tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "run", synth_log(varied_motions()[:3]), StoragePlugin.MCAP)
    options = ImportOptions(format="rosbag", odom_topic="/mocap/robot/pose", truth_topic="/odom")
    with pytest.raises(RecordingError, match=r"--odom-topic: topic '/mocap/robot/pose' is geom"):
        read_recording([bag], optiodom_robot(), options)


def test_stamps_on_clocks_that_do_not_overlap_are_refused(tmp_path: Path) -> None:
    log = synth_log(varied_motions()[:3])
    shifted = SynthLog(log.t_s, log.odometry, log.truth, log.true_changes)
    bag = tmp_path / "run"
    with Writer(bag, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        odom = writer.add_connection("/odom", "nav_msgs/msg/Odometry", typestore=STORE)
        truth = writer.add_connection(
            "/ground_truth", "geometry_msgs/msg/PoseStamped", typestore=STORE
        )
        for index, t in enumerate(shifted.t_s):
            ns = round(t * 1e9)
            writer.write(
                odom,
                ns,
                STORE.serialize_cdr(_odometry(t, log.odometry[index]), "nav_msgs/msg/Odometry"),
            )
            # the capture stamped with its own clock, started at zero
            message = _pose_stamped(t - log.t_s[0], log.truth[index])
            writer.write(truth, ns, STORE.serialize_cdr(message, "geometry_msgs/msg/PoseStamped"))
    with pytest.raises(RecordingError, match=r"run: the clocks do not overlap: odometry 1000.0"):
        read_recording([bag], optiodom_robot(), ImportOptions(format="rosbag"))


def test_not_a_bag_is_refused(tmp_path: Path) -> None:
    folder = tmp_path / "empty"
    folder.mkdir()
    with pytest.raises(RecordingError, match=r"empty: not a ROS 2 bag folder"):
        read_recording([folder], optiodom_robot(), ImportOptions(format="rosbag"))
    junk = tmp_path / "junk.mcap"
    junk.write_bytes(b"not an mcap file at all")
    with pytest.raises(RecordingError, match=r"junk.mcap: cannot read the bag"):
        read_recording([junk], optiodom_robot(), ImportOptions(format="rosbag"))


def test_header_stamps_that_go_back_name_the_message(tmp_path: Path) -> None:
    log = synth_log(varied_motions()[:3])
    t = log.t_s.copy()
    t[30] = t[28]  # stamped (and written) earlier: the bag holds it as its 30th message
    bag = write_bag(
        tmp_path / "run", SynthLog(t, log.odometry, log.truth, log.true_changes), StoragePlugin.MCAP
    )
    options = ImportOptions(format="rosbag", truth_topic="/mocap/robot/pose")
    with pytest.raises(
        RecordingError,
        match=r"run /odom message 30: header.stamp must increase, got 1000.56 after 1000.56 "
        r"\(message 29\)",
    ):
        read_recording([bag], optiodom_robot(), options)
