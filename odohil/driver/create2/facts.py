"""The iRobot Create 2's facts (:class:`~odohil.science.robot_facts.RobotFacts`):
what the rest of odohil may know about this robot, read through the registry
(odohil/session/robots/registry.py ``robot_facts``)."""

from __future__ import annotations

from odohil.driver.create2.link import REPLY_TIMEOUT_S
from odohil.protocol.create2.geometry import CREATE2_GEOMETRY
from odohil.protocol.create2.opcodes import BAUD_RATES, DEFAULT_BAUD
from odohil.science.limits import L_MAX_M
from odohil.science.robot_facts import DRIVE_KEYS, FakeFacts, RobotFacts

__all__ = ["CREATE2_FACTS", "CREATE2_GEOMETRY", "MIN_LEG_M", "STEP_TOLERANCE_M"]

STEP_TOLERANCE_M = 0.01
"""Largest distance (per wheel) a step may end from its target, m (the
driver's end-of-step check, odohil/driver/create2/robot.py)."""
MIN_LEG_M = 5 * STEP_TOLERANCE_M
"""Shortest leg a session drives, m: the end-of-step tolerance is at most a
fifth of it."""

CREATE2_FACTS = RobotFacts(
    name="create2",
    label="iRobot Create 2",
    baud_rates=BAUD_RATES,
    default_baud=DEFAULT_BAUD,
    min_leg_m=MIN_LEG_M,
    max_leg_m=L_MAX_M,
    turns_exact=False,
    robot_keys=(*DRIVE_KEYS, "full_mode"),
    drive=CREATE2_GEOMETRY,
    reply_timeout_s=REPLY_TIMEOUT_S,
    reply_timeout_range_s=(0.05, 60.0),  # at least three 15 ms stream frames
    fake=FakeFacts(
        url_scheme="fakecreate2:",
        truth_client="fakes.create2.truth:Create2TruthClient",
        emulator="fakes.create2.run:emulate",
        emulate_time_scale=1.0,
        demo_time_scale=10.0,
        # a leg ends on 15 ms readings and a stop sent by the host: on a faster
        # clock a late reading ends a leg centimetres long; the fake's clock then
        # advances at most one 15 ms tick between two driver calls
        # (fakes/create2/clock.py); a read that waits for the next frame moves
        # the fake's clock to it instead of sleeping (skip_waits: the same frames
        # at the same simulated times, without the 15 ms of wall time each)
        demo_url_options=(("max_gap_ms", 15.0), ("skip_waits", 1.0)),
    ),
)
"""A differential drive: its spins carry error (turns_exact false), its legs
are counted on 16-bit encoders read incrementally (no wire limit on a leg:
the science commands' longest, 100 m), its constants from the description."""
