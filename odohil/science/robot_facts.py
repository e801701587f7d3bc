"""What a robot backend declares about its robot: :class:`RobotFacts`.

The type only: each backend fills one (odohil/driver/<robot>/facts.py) and the
session reads it through the registry (odohil/session/robots/registry.py
``robot_facts``). It lives in the science layer so that every layer can take
it as a value (the robot description's parser checks a description against
it); no robot's numbers are written here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from odohil.errors import ParameterError
from odohil.science.diff_drive import DiffDriveGeometry

DRIVE_KEYS = ("counts_per_rev", "wheel_diameter_m", "wheel_base_m")
"""The ``[robot]`` keys of a differential drive's kinematic constants."""


@dataclass(frozen=True)
class FakeFacts:
    """A backend's fake robot for tests and demos (fakes/).

    Attributes:
        url_scheme: the pyserial URL scheme its in-process fake serves (e.g.
            ``fakerobot:``); an open port of that scheme carries the true pose.
        truth_client: ``"module:Class"`` of the client that reads a fake
            process's truth socket (methods ``open``, ``close``, ``true_pose``).
        emulator: ``"module:function"`` that ``odohil emulate`` calls to
            serve the fake on a pty (given a ``fakes.launch.EmulateOptions``).
        emulate_time_scale: ``odohil emulate``'s default time scale
            (simulated seconds per wall second).
        demo_time_scale: ``odohil demo``'s time scale.
        demo_url_options: more URL options of ``odohil demo``'s fake
            (name, value), e.g. a clock step limit the time scale needs.
    """

    url_scheme: str
    truth_client: str
    emulator: str = ""
    emulate_time_scale: float = 1.0
    demo_time_scale: float = 1.0
    demo_url_options: tuple[tuple[str, float], ...] = ()


@dataclass(frozen=True)
class RobotFacts:
    """One robot backend's facts, in SI units.

    Attributes:
        name: the backend's name in the ``odohil.robots`` entry-point group
            (a description's ``[robot] protocol``).
        label: the robot's name for people (help texts), e.g. ``iRobot Create 2``.
        baud_rates: the line speeds it speaks, bit/s (checked before anything is sent).
        default_baud: the line speed when neither the command line nor the
            description gives one, bit/s (one of ``baud_rates``).
        min_leg_m: shortest leg it drives, m.
        max_leg_m: longest leg it drives in one command, m.
        max_turn_rad: largest in-place turn it drives in one command, rad.
        turns_exact: whether its in-place turns carry no error (a synchronous
            drive): the default of ``[robot] turns_exact``.
        robot_keys: the ``[robot]`` keys of a robot description it reads
            (besides ``protocol`` and ``turns_exact``).
        drive: a differential drive's nominal kinematic constants, the
            defaults of the description's ``counts_per_rev``,
            ``wheel_diameter_m`` and ``wheel_base_m``; None: not a
            differential drive (those keys are then refused).
        fake: its fake robot (None: it has none).
        reply_timeout_s: how long its driver waits for a reply by default, s
            (the default of the description's ``[serial] timeout_s``).
        reply_timeout_range_s: the ``[serial] timeout_s`` it accepts, s (low, high).
    """

    name: str
    label: str
    baud_rates: tuple[int, ...]
    default_baud: int
    min_leg_m: float
    max_leg_m: float
    max_turn_rad: float = math.inf
    turns_exact: bool = False
    robot_keys: tuple[str, ...] = ()
    drive: DiffDriveGeometry | None = None
    fake: FakeFacts | None = None
    reply_timeout_s: float = 1.0
    reply_timeout_range_s: tuple[float, float] = (0.05, 60.0)

    def __post_init__(self) -> None:
        if self.default_baud not in self.baud_rates:
            raise ParameterError(
                f"{self.name}: default baud {self.default_baud} is not one of {self.baud_rates}"
            )
        if not 0 < self.min_leg_m < self.max_leg_m:
            raise ParameterError(
                f"{self.name}: legs must range over 0 < min < max, got "
                f"{self.min_leg_m!r}..{self.max_leg_m!r} m"
            )

    def leg_range_text(self) -> str:
        """E.g. ``at least 0.05 and at most 83.2282 m``."""
        return f"at least {self.min_leg_m:g} and at most {self.max_leg_m:g} m"

    def check_leg(self, l_m: float, label: str = "l") -> float:
        """``l_m`` if a leg of that length (m) is within what this robot
        drives, else ParameterError naming ``label``, the robot and the range."""
        if isinstance(l_m, bool) or not isinstance(l_m, int | float):
            raise ParameterError(f"{label} must be a number of metres, got {l_m!r}")
        if not (math.isfinite(l_m) and self.min_leg_m <= l_m <= self.max_leg_m):
            raise ParameterError(
                f"{label} must be {self.leg_range_text()} for the {self.label} "
                f"({self.name}), got {l_m!r}"
            )
        return l_m

    def check_reply_timeout(self, timeout_s: float, label: str = "timeout_s") -> float:
        """``timeout_s`` if its driver accepts that reply timeout (s), else
        ParameterError naming ``label``, the range and the robot."""
        low, high = self.reply_timeout_range_s
        number = not isinstance(timeout_s, bool) and isinstance(timeout_s, int | float)
        if not (number and math.isfinite(timeout_s) and low <= timeout_s <= high):
            raise ParameterError(
                f"{label} must be at least {low:g} and at most {high:g} s for the "
                f"{self.label} ({self.name}), got {timeout_s!r}"
            )
        return float(timeout_s)

    def speaks(self, baud: int) -> bool:
        """Whether ``baud`` is one of its line speeds."""
        return baud in self.baud_rates

    def rates_text(self) -> str:
        """Its line speeds, e.g. ``4800, 9600, 19200, 38400``."""
        return ", ".join(map(str, self.baud_rates))
