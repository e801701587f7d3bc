"""The Nomad 150's facts (:class:`~odohil.science.robot_facts.RobotFacts`):
what the rest of odohil may know about this robot, read through the registry
(odohil/session/robots/registry.py ``robot_facts``)."""

from __future__ import annotations

from odohil.driver.nomad.link import BAUD_RATES, DEFAULT_BAUD, NORMAL_TIMEOUT_S
from odohil.protocol.nomad.limits import MAX_LEG_M, MIN_LEG_M
from odohil.protocol.nomad.numbers import S16_MAX
from odohil.protocol.nomad.wire_units import wire_to_radians
from odohil.science.robot_facts import FakeFacts, RobotFacts

NOMAD150_FACTS = RobotFacts(
    name="nomad150",
    label="Nomad 150",
    baud_rates=BAUD_RATES,
    default_baud=DEFAULT_BAUD,
    min_leg_m=MIN_LEG_M,
    max_leg_m=MAX_LEG_M,
    max_turn_rad=wire_to_radians(S16_MAX),
    turns_exact=True,
    robot_keys=(),
    drive=None,
    reply_timeout_s=NORMAL_TIMEOUT_S,
    reply_timeout_range_s=(0.05, 60.0),
    fake=FakeFacts(
        url_scheme="fakerobot:",
        truth_client="fakes.nomad.truth:TruthClient",
        emulator="fakes.nomad.run:emulate",
        emulate_time_scale=1.0,
        demo_time_scale=20000.0,
    ),
)
"""A synchronous drive (turns exact) whose ``pr`` carries a leg as an s16 in
0.1 inch (odohil/protocol/nomad/limits.py) and a turn as an s16 in 0.1 degree;
it reads no ``[robot]`` constants."""
