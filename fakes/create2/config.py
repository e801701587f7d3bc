"""Settings of one fake Create 2, and its faults and safety events."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from odohil.errors import ParameterError
from odohil.protocol.create2.geometry import CREATE2_GEOMETRY
from odohil.protocol.create2.opcodes import BAUD_RATES, DEFAULT_BAUD
from odohil.science.diff_drive import DiffDriveErrors, DiffDriveGeometry
from odohil.science.parameters import ErrorParameters

CREATE2_TRUTH = ErrorParameters.from_paper_units(-0.35, -0.015, 0.02, 5e-5)
"""The fake's default straight-leg errors (paper units: -0.35 deg/m, -1.5 %,
0.02 deg^2/m, 5e-5 m): a Create 2 with slightly unequal wheels."""
DEFAULT_TURN_SCALE = 0.012
"""Default e_turn: an in-place turn really turns 1.2 % more than the encoders say."""
DEFAULT_SPIN_K = 2e-4
"""Default K_spin, rad^2 per rad turned in place."""

DEFAULT_MODE_CHANGE_S = 0.05
"""How long a Safe or Full command takes to take effect, wall s (C28): no
source gives it; libcreate waits 100 ms after a mode command, pycreate2 0.5 s
("so the bot has time to change modes")."""
PASSIVE_SLEEP_S = 300.0
"""Passive mode sleeps after 5 minutes without a command (p.7), simulated s."""
HOST_BOUND_S = 0.045
"""How far (wall s) the pty fake's motion runs past the newest instant up to
which the host has read everything the fake wrote
(``Create2Engine(host_bound_s=...)``, fakes/create2/clock.py
``ReadBoundClock``): three stream periods, so a host that reads each frame
within 30 ms never meets it, and a host starved for longer finds its wheels at
most 45 ms (times the time scale) of driving past its last reading."""

EVENTS = (
    "wheel_drop",
    "wheel_drop_left",
    "wheel_drop_right",
    "cliff",
    "cliff_left",
    "cliff_front_left",
    "cliff_front_right",
    "cliff_right",
    "bump",
    "bump_left",
    "bump_right",
    "charger",
    "clear",
    "wake",
)
"""Safety events a test hook may inject (C12): a wheel drop or cliff stops the
robot and drops Safe to Passive; a bump only sets packet 7; ``charger`` drops
Safe or Full to Passive (a powered charger); ``clear`` clears every sensor;
``wake`` wakes the robot after Power (133)."""

LINE_FAULTS = ("disconnect", "mute", "garble", "stall", "drag")
"""Faults of the line or the wheels: ``disconnect`` cuts the line, ``mute``
stops every reply and frame, ``garble`` flips one bit of the next output,
``stall`` stops both wheels and their encoders while commands still say move,
``drag`` makes both wheels turn at :data:`DRAG_FACTOR` of the commanded speed
(a dragged load, a flat battery: the encoders count on, a leg takes 20 times
as long)."""
DRAG_FACTOR = 0.05
"""Fraction of the commanded speed the wheels turn at after a ``drag`` fault."""

FAULT_NAMES = EVENTS + LINE_FAULTS


@dataclass(frozen=True)
class FaultSpec:
    """A fault or event that fires once the robot has driven ``at_m`` encoder
    metres since power-on (mean of the wheels' travel); 0 fires on the first
    motion."""

    name: str
    at_m: float = 0.0

    def __post_init__(self) -> None:
        if self.name not in FAULT_NAMES:
            raise ParameterError(f"unknown fault {self.name!r}; one of {', '.join(FAULT_NAMES)}")
        if not (math.isfinite(self.at_m) and self.at_m >= 0):
            raise ParameterError(f"a fault's distance must be >= 0 m, got {self.at_m!r}")

    def __str__(self) -> str:
        return f"{self.name}@{self.at_m:g}"


def parse_fault(text: str) -> FaultSpec:
    """``NAME`` or ``NAME@METRES`` (see :class:`FaultSpec`)."""
    name, _, at = text.partition("@")
    try:
        at_m = float(at) if at else 0.0
    except ValueError as exc:
        raise ParameterError(f"fault {text!r}: {at!r} is not a distance in metres") from exc
    return FaultSpec(name.strip(), at_m)


@dataclass(frozen=True)
class Create2Config:
    """Everything that makes one fake Create 2 behave as it does.

    Attributes:
        errors: the true robot's wheel, wheel-base and slip errors.
        geometry: the nominal constants its encoders count with (C4).
        seed: seed of the noise (None: fresh entropy).
        time_scale: simulated seconds per wall second (motion only); the
            15 ms sensor tick and the line count wall seconds.
        baud: line rate at power-on (C1).
        faults: faults and events to fire on the way.
        segment_m: longest segment of the discrete error model, m.
        encoder_origin: encoder counts at power-on and Reset (C3; e.g. 65000
            exercises the wrap).
        mode_offset: added to packet 35 (1 imitates the 6xx bug, C7).
        angle_bug: packet 20 reports degrees x 0.324056 (firmware <= 3.4.0, C11).
        firmware: the version string of the Reset banner (C14).
        mode_change_s: wall seconds a Safe or Full command takes to take
            effect; commands before then find the old mode (C28).
        passive_sleep_s: simulated seconds in Passive without a command
            before the robot sleeps (p.7: 5 minutes); None never sleeps (C27).
    """

    errors: DiffDriveErrors = field(
        default_factory=lambda: DiffDriveErrors.from_parameters(
            CREATE2_TRUTH,
            turn_scale=DEFAULT_TURN_SCALE,
            k_spin=DEFAULT_SPIN_K,
            wheel_base_m=CREATE2_GEOMETRY.wheel_base_m,
        )
    )
    geometry: DiffDriveGeometry = CREATE2_GEOMETRY
    seed: int | None = None
    time_scale: float = 1.0
    baud: int = DEFAULT_BAUD
    faults: tuple[FaultSpec, ...] = ()
    segment_m: float = 0.001
    encoder_origin: int = 0
    mode_offset: int = 0
    angle_bug: bool = False
    firmware: str = "r3-robot/tags/release-3.7.7:6913"
    mode_change_s: float = DEFAULT_MODE_CHANGE_S
    passive_sleep_s: float | None = PASSIVE_SLEEP_S

    def __post_init__(self) -> None:
        if not (math.isfinite(self.time_scale) and self.time_scale > 0):
            raise ParameterError(f"time_scale must be positive, got {self.time_scale}")
        if not (math.isfinite(self.segment_m) and self.segment_m > 0):
            raise ParameterError(f"segment_m must be positive, got {self.segment_m}")
        if not 0 <= self.encoder_origin <= 0xFFFF:
            raise ParameterError(f"encoder_origin must be 0..65535, got {self.encoder_origin}")
        if self.mode_offset not in (0, 1):
            raise ParameterError(f"mode_offset must be 0 or 1, got {self.mode_offset}")
        if self.baud not in BAUD_RATES:
            raise ParameterError(f"baud must be one of {BAUD_RATES}, got {self.baud}")
        if not (math.isfinite(self.mode_change_s) and 0.0 <= self.mode_change_s <= 10.0):
            raise ParameterError(f"mode_change_s must be in [0, 10] s, got {self.mode_change_s}")
        sleep = self.passive_sleep_s
        if sleep is not None and not (math.isfinite(sleep) and sleep > 0):
            raise ParameterError(f"passive_sleep_s must be positive or None, got {sleep}")


def build_config(
    *,
    seed: int | None = None,
    params: ErrorParameters = CREATE2_TRUTH,
    turn_scale: float = DEFAULT_TURN_SCALE,
    spin_k: float = DEFAULT_SPIN_K,
    time_scale: float = 1.0,
    baud: int = DEFAULT_BAUD,
    faults: list[str] | tuple[str, ...] = (),
    encoder_origin: int = 0,
    mode_offset: int = 0,
    angle_bug: bool = False,
    mode_change_s: float = DEFAULT_MODE_CHANGE_S,
    passive_sleep_s: float | None = PASSIVE_SLEEP_S,
) -> Create2Config:
    """A :class:`Create2Config` from command-line style values."""
    geometry = CREATE2_GEOMETRY
    return Create2Config(
        errors=DiffDriveErrors.from_parameters(
            params, turn_scale=turn_scale, k_spin=spin_k, wheel_base_m=geometry.wheel_base_m
        ),
        geometry=geometry,
        seed=seed,
        time_scale=time_scale,
        baud=baud,
        faults=tuple(parse_fault(text) for text in faults),
        encoder_origin=encoder_origin,
        mode_offset=mode_offset,
        angle_bug=angle_bug,
        mode_change_s=mode_change_s,
        passive_sleep_s=passive_sleep_s,
    )
