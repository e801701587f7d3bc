"""The motion-capture client against small loopback senders: a good stream,
and each way a stream can be unusable (silent, stale, closed, not still,
jumping, malformed lines), each a MeasurementError naming the URL."""

from __future__ import annotations

import math
import re
import time
from pathlib import Path

import numpy as np
import pytest

from fakes.nomad.process import EmulatorProcess
from fakes.nomad.truth import TruthClient
from odohil.errors import ConnectionFailedError, JournalError, MeasurementError, ParameterError
from odohil.session.journal.state import validate_header
from odohil.session.measure.mocap import PoseStream, StillCriteria, parse_tcp_url, take_still_pose
from odohil.session.measure.mocap.still import judge_window
from odohil.session.measure.mocap.stream import StreamedPose, StreamStatus
from tests.session.mocap_server import FrameServer, pose_line, republish_truth

SIGMA = (0.001, 0.001, 0.002)
"""pose_sigma of these tests: 1 mm, 1 mm, 2 mrad."""
FAST = StillCriteria(window_s=0.3, first_pose_timeout_s=0.5, stale_s=0.3)
WORLD = (1.5, -2.0, 3.1)
"""A pose at rest, heading near pi so that the noise wraps it."""


def noisy_at_rest(seed: int, sigma: tuple[float, float, float] = SIGMA) -> FrameServer:
    rng = np.random.default_rng(seed)

    def frame(t: float) -> bytes:
        e = rng.normal(0.0, 1.0, 3) * np.array(sigma)
        theta = math.remainder(WORLD[2] + e[2], 2 * math.pi)
        return pose_line(t, WORLD[0] + e[0], WORLD[1] + e[1], theta)

    return FrameServer(frame)


def test_a_still_robot_gives_the_median_pose_with_its_spread() -> None:
    with noisy_at_rest(1) as server, PoseStream(server.url) as stream:
        still = take_still_pose(stream, SIGMA, FAST)
    assert still.n_poses >= 15  # 100 Hz over 0.3 s, on a busy machine too
    assert still.pose[0] == pytest.approx(WORLD[0], abs=0.001)
    assert still.pose[1] == pytest.approx(WORLD[1], abs=0.001)
    # the heading's median is taken across the +-pi seam, not averaged to ~0
    assert math.remainder(still.pose[2] - WORLD[2], 2 * math.pi) == pytest.approx(0, abs=0.002)
    # spread: the frame noise, estimated from successive differences
    assert still.spread[0] == pytest.approx(SIGMA[0], rel=0.5)
    assert still.spread[2] == pytest.approx(SIGMA[2], rel=0.5)
    assert still.malformed == 0
    assert still.t_span[0] < still.t_span[1]
    assert set(still.to_json()) == {"pose", "n_poses", "spread", "t_span", "malformed"}


def test_nobody_listening_is_a_connection_error_naming_the_url() -> None:
    with FrameServer(lambda t: None) as server:
        url = server.url
    with pytest.raises(ConnectionFailedError, match=f"{url}: cannot connect"):
        PoseStream(url).open()


def test_a_silent_stream_is_refused_naming_the_url() -> None:
    with FrameServer(lambda t: None) as server, PoseStream(server.url) as stream:
        url = server.url
        with pytest.raises(MeasurementError, match=f"{url}: silent stream: no pose"):
            take_still_pose(stream, SIGMA, FAST)


def test_a_stream_that_stops_is_stale() -> None:
    def frame(t: float) -> bytes | None:
        return pose_line(t, *WORLD) if t < 0.2 else None

    with FrameServer(frame) as server, PoseStream(server.url) as stream:
        assert stream.wait_for_pose(1.0)
        # the window then ends 0.65 s after the first pose: the newest is 0.45 s old
        time.sleep(0.25)
        with pytest.raises(
            MeasurementError,
            match=rf"{server.url}: stale stream: the newest pose arrived 0\.\d+ s ago "
            r"\(more than 0\.3 s, by this computer's clock\)",
        ):
            take_still_pose(stream, SIGMA, FAST)


def test_a_frozen_sender_repeating_its_last_frame_is_stale() -> None:
    def frame(t: float) -> bytes:
        return pose_line(min(t, 0.1), *WORLD)  # t stops advancing after 0.1 s

    with FrameServer(frame) as server, PoseStream(server.url) as stream:
        assert stream.wait_for_pose(1.0)
        time.sleep(0.25)  # the newest accepted pose is 0.55 s old at the window's end
        with pytest.raises(MeasurementError, match=r"stale stream.*'t' .* does not increase"):
            take_still_pose(stream, SIGMA, FAST)


def test_a_sender_that_hangs_up_is_named() -> None:
    with (
        FrameServer(lambda t: pose_line(t, *WORLD), lifetime_s=0.2) as server,
        PoseStream(server.url) as stream,
    ):
        time.sleep(0.25)  # the sender hung up 0.2 s after the start
        with pytest.raises(MeasurementError, match="the sender closed the connection"):
            take_still_pose(stream, SIGMA, FAST)


def test_a_moving_robot_is_not_still() -> None:
    def frame(t: float) -> bytes:
        return pose_line(t, WORLD[0] + 0.1 * t, WORLD[1], WORLD[2])  # 10 cm/s

    with (
        FrameServer(frame) as server,
        PoseStream(server.url) as stream,
        pytest.raises(
            MeasurementError,
            match=rf"{server.url}: the robot is not still: its x moved .* mm between the two "
            r"halves of the 0\.3 s still window \(medians\), more than 5 x pose_sigma = 5 mm",
        ),
    ):
        take_still_pose(stream, SIGMA, FAST)


def _square(t: float) -> int:
    """0 and 1 by turns every 0.12 s: any still window holds a jump, however
    late the sender's thread starts on a busy machine."""
    return int(t / 0.12) % 2


def test_a_jump_in_the_window_is_refused() -> None:
    def frame(t: float) -> bytes:
        return pose_line(t, WORLD[0], WORLD[1] + 0.03 * _square(t), WORLD[2])

    with (
        FrameServer(frame) as server,
        PoseStream(server.url) as stream,
        pytest.raises(
            MeasurementError, match=rf"{server.url}: the pose jumps by 30 mm in y .* marker swap"
        ),
    ):
        take_still_pose(stream, SIGMA, FAST)


def test_a_heading_jump_is_refused_in_degrees() -> None:
    def frame(t: float) -> bytes:
        return pose_line(t, WORLD[0], WORLD[1], WORLD[2] - 0.5 * _square(t))

    with (
        FrameServer(frame) as server,
        PoseStream(server.url) as stream,
        pytest.raises(MeasurementError, match=r"jumps by 28\.6 deg in theta"),
    ):
        take_still_pose(stream, SIGMA, FAST)


def test_malformed_lines_are_counted_and_reported_never_fatal() -> None:
    bad = [
        b"not json\n",
        b"[1, 2, 3]\n",
        b'{"t": 1.0, "x": 1.0, "y": 2.0}\n',
        b'{"t": 1.0, "x": "1", "y": 2.0, "theta": 0}\n',
        b'{"t": 1.0, "x": NaN, "y": 2.0, "theta": 0}\n',
        b'{"t": 1.0, "x": true, "y": 2.0, "theta": 0}\n',
        b"\xff\xfe\n",
        b"x" * 5000 + b"\n",
    ]
    sent = {"n": 0}

    def frame(t: float) -> bytes:
        sent["n"] += 1
        if sent["n"] % 2:
            return bad[(sent["n"] // 2) % len(bad)]
        return pose_line(t, *WORLD, extra_key="ignored")

    with FrameServer(frame) as server, PoseStream(server.url) as stream:
        still = take_still_pose(stream, SIGMA, FAST)
        status = stream.status()
    assert still.pose[:2] == pytest.approx(WORLD[:2])
    assert still.malformed >= 10
    assert still.to_json()["malformed"] == still.malformed
    assert still.last_malformed
    assert status.n_poses > 10


def test_only_malformed_lines_is_silent_with_the_reason() -> None:
    with (
        FrameServer(lambda t: b'{"x": 1}\n') as server,
        PoseStream(server.url) as stream,
        pytest.raises(
            MeasurementError,
            match=r"silent stream.*malformed line\(s\) dropped; last: 't' is missing",
        ),
    ):
        take_still_pose(stream, SIGMA, FAST)


@pytest.mark.parametrize(
    "url",
    ["tcp://127.0.0.1", "udp://127.0.0.1:5000", "tcp://:5000", "tcp://h:0", "tcp://h:99999",
     "tcp://h:5000/path", "tcp://h:x", "127.0.0.1:5000"],
)  # fmt: skip
def test_a_bad_url_names_the_form(url: str) -> None:
    with pytest.raises(ParameterError, match=r"tcp://HOST:PORT"):
        parse_tcp_url(url)


def test_close_ends_the_reader_thread() -> None:
    with noisy_at_rest(2) as server:
        stream = PoseStream(server.url)
        stream.open()
        assert stream.wait_for_pose(1.0)
        thread = stream._thread
        stream.close()
        stream.close()
        assert thread is not None
        assert not thread.is_alive()
        assert stream.status().closed == "closed by odohil"


def test_the_truth_republisher_shows_the_fake_robot_in_its_world_frame(tmp_path: Path) -> None:
    rotation, shift = 2.0, (4.0, -1.5)
    args = ["--seed", "3", "--time-scale", "20000", "--no-pacing"]
    args += ["--truth-socket", str(tmp_path / "t.sock")]
    with EmulatorProcess(args) as robot, TruthClient(robot.truth_socket) as truth:

        def true_pose() -> tuple[float, float, float]:
            snap = truth.snapshot()
            return (snap.true_x_m, snap.true_y_m, snap.true_theta_rad)

        frame = republish_truth(
            true_pose, rotation_rad=rotation, shift_m=shift, sigma=SIGMA, seed=1
        )
        with FrameServer(frame) as server, PoseStream(server.url) as stream:
            still = take_still_pose(stream, SIGMA, FAST)
        x, y, theta = true_pose()
    c, s = math.cos(rotation), math.sin(rotation)
    assert still.pose[0] == pytest.approx(shift[0] + c * x - s * y, abs=0.001)
    assert still.pose[1] == pytest.approx(shift[1] + s * x + c * y, abs=0.001)
    assert math.remainder(still.pose[2] - theta - rotation, 2 * math.pi) == pytest.approx(
        0, abs=0.002
    )


def _window(values: np.ndarray, rate_hz: float = 100.0) -> list[StreamedPose]:
    return [StreamedPose(i / rate_hz, i / rate_hz, *row) for i, row in enumerate(values)]


def test_frame_jitter_well_above_pose_sigma_is_no_false_alarm() -> None:
    # pose_sigma is the still pose's (a median of ~50 frames): the frames may
    # jitter five times more; 2000 windows at rest are all accepted
    rng = np.random.default_rng(11)
    jitter = 5.0 * np.array(SIGMA)
    status = StreamStatus(50, 0, "", 0.0, 0.0, "")
    medians = []
    for _ in range(2000):
        values = np.array(WORLD) + rng.normal(0.0, 1.0, (50, 3)) * jitter
        still = judge_window(_window(values), SIGMA, FAST, "tcp://test:1", status)
        medians.append(still.pose[:2])
    # the median of 50 frames: about 1.2533 x jitter / sqrt(50) = 0.89 mm here
    assert np.std(np.array(medians)[:, 0]) == pytest.approx(1.2533 * jitter[0] / 50**0.5, rel=0.1)


def test_a_slow_drift_under_heavy_jitter_is_not_still() -> None:
    rng = np.random.default_rng(12)
    values = np.array(WORLD) + rng.normal(0.0, 1.0, (50, 3)) * 5.0 * np.array(SIGMA)
    values[:, 1] += 0.06 * np.arange(50) / 100.0  # 6 cm/s: 15 mm between the halves' medians
    status = StreamStatus(50, 0, "", 0.0, 0.0, "")
    with pytest.raises(MeasurementError, match=r"not still: its y moved [\d.]+ mm"):
        judge_window(_window(values), SIGMA, FAST, "tcp://test:1", status)


def test_a_journal_header_names_its_stream_by_a_tcp_url() -> None:
    validate_header({"measure": "tcp", "settings": {"mocap_url": "tcp://10.0.0.5:5555"}})
    with pytest.raises(JournalError, match=r"settings\.mocap_url: .*tcp://HOST:PORT"):
        validate_header({"measure": "tcp", "settings": {"mocap_url": "10.0.0.5:5555"}})
    with pytest.raises(JournalError, match=r"settings\.mocap_url must be str"):
        validate_header({"measure": "tcp", "settings": {"mocap_url": 5555}})
    with pytest.raises(JournalError, match=r"measure must be one of fake, file, operator, tcp"):
        validate_header({"measure": "udp"})


# -- issue 17: one bad time stamp is dropped and counted, never poisons the stream --


def _stamped(bad: dict[int, float]) -> FrameServer:
    """A robot at rest whose frame number n is stamped ``bad[n]`` instead of
    its time (a corrupt stamp, a clock glitch)."""
    sent = {"n": 0}

    def frame(t: float) -> bytes:
        n = sent["n"]
        sent["n"] += 1
        return pose_line(bad.get(n, t), *WORLD)

    return FrameServer(frame)


@pytest.mark.parametrize(
    ("bad", "reason"),
    [
        ({5: 1e12}, r"'t' 1e\+12 s is [\d.e+]+ s after the previous frame's"),
        ({0: 1e12}, r"'t' stepped from 1e\+12 s"),  # the first frame's stamp is the bad one
        ({5: -3.0}, r"'t' -3 s does not increase"),
    ],
    ids=["far-future", "first-far-future", "out-of-order"],
)
def test_one_bad_time_stamp_is_dropped_and_counted(bad: dict[int, float], reason: str) -> None:
    with _stamped(bad) as server, PoseStream(server.url) as stream:
        assert stream.wait_for_pose(1.0)
        time.sleep(0.2)  # the bad frame is behind us, and as many good ones
        still = take_still_pose(stream, SIGMA, FAST)
        status = stream.status()
    assert still.pose == pytest.approx(WORLD)
    assert still.n_poses >= 15
    assert status.n_bad_time == 1
    assert still.to_json()["bad_time_stamps"] == 1
    assert re.search(reason, status.last_bad_time), status.last_bad_time


def test_a_stream_whose_every_stamp_is_bad_ends_with_that_reason() -> None:
    rng = np.random.default_rng(3)

    def frame(t: float) -> bytes:
        return pose_line(float(rng.uniform(0.0, 1e6)), *WORLD)  # stamps in random order

    with FrameServer(frame) as server, PoseStream(server.url) as stream:
        assert stream.wait_for_pose(1.0)
        with pytest.raises(
            MeasurementError,
            match=r"motion capture .*frame\(s\) with a bad time stamp dropped.*does the "
            r"sender stamp its frames with one steady clock, in seconds\?",
        ):
            take_still_pose(stream, SIGMA, FAST)


def test_a_sender_clock_that_steps_is_followed_after_a_few_frames() -> None:
    # an NTP step of the sender's clock: every later frame is an hour ahead
    def frame(t: float) -> bytes:
        return pose_line(t + (3600.0 if t > 0.1 else 0.0), *WORLD)

    with FrameServer(frame) as server, PoseStream(server.url) as stream:
        assert stream.wait_for_pose(1.0)
        time.sleep(0.3)
        still = take_still_pose(stream, SIGMA, FAST)
        status = stream.status()
    assert still.n_poses >= 15
    assert 1 <= status.n_bad_time <= 10
    assert still.t_span[0] > 3600.0


def test_the_farthest_point_of_a_path_ignores_one_stray_frame() -> None:
    # at 200 Hz, the path's times halved: as many frames 8 mm apart as at 100 Hz
    def frame(t: float) -> bytes:
        if 0.25 < t < 0.26:  # one or two frames of another body, 10 m away
            return pose_line(t, WORLD[0] + 10.0, WORLD[1], WORLD[2])
        out = max(0.0, 0.5 - 2.0 * abs(t - 0.3))  # out to 0.5 m at t = 0.3 s, and back
        return pose_line(t, WORLD[0], WORLD[1] + out, WORLD[2])

    with FrameServer(frame, rate_hz=200.0) as server, PoseStream(server.url) as stream:
        assert stream.wait_for_pose(1.0)
        stream.track_from(WORLD[0], WORLD[1])
        begin = stream.clock()
        time.sleep(0.65)
        excursion, frames = stream.excursion_between(begin, stream.clock())
        none, zero = stream.excursion_between(begin - 10.0, begin - 5.0)
    assert frames >= 60
    assert excursion == pytest.approx(0.5, abs=0.03)
    assert (none, zero) == (None, 0)
