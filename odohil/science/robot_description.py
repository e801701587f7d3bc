"""The robot description: where the marking screws are, how good a tape reading is,
which cross distances are measured, and how to reach the robot.

Parsed from TOML text (the file itself is read by :mod:`odohil.session.robots.description`)::

    [screws]                 # positions in the robot frame (x forward, y left), metres
    A = [0.20, 0.0]
    B = [-0.10, 0.173]
    C = [-0.10, -0.173]
    [measurement]
    sigma_m = 0.001          # standard deviation of one tape reading, metres
    cross = [["A", "B"], ["B", "C"]]  # start mark of A to end mark of B, B to C
    pose_sigma = [0.0005, 0.0005, 0.001]  # optional, motion capture: one still pose's
                             # standard deviations (x m, y m, theta rad), world axes
    still_window_s = 0.5     # optional, motion capture: how long a still pose's
                             # frames are collected, s (default 0.5)
    [robot]                  # optional: which driver backend speaks to it
    protocol = "nomad150"    # an odohil.robots entry point (default nomad150)
    # differential drives (the create2 backend, logs with wheel counts; defaults:
    # the backend's nominal constants, docs/create2.md): counts_per_rev,
    # wheel_diameter_m (or [left, right]), wheel_base_m; full_mode (create2)
    # turns_exact: whether in-place turns carry no error (a synchronous drive);
    # default: the backend's (false for a protocol with no installed backend:
    # a differential drive's spins carry error), so that the planner, wizard
    # and run use turn-free designs
    [serial]                 # optional, for the driver
    port = "/dev/ttyUSB0"    # or any pyserial URL
    baud = 9600              # one of the backend's line speeds (default: its own)
    timeout_s = 1.0          # the driver's reply timeout, s (default and range: the backend's)
    [priors]                 # optional: belief in the four parameters before any trial
    E_R_deg_per_m = -0.202   # (paper units; defaults: the paper's Nomad 150 values)
    E_R_sd_deg_per_m = 0.5   # one standard deviation of that belief
    E_T = -0.02
    E_T_sd = 0.05
    K_theta_deg2_per_m = 0.012
    K_theta_sd_deg2_per_m = 0.05
    K_rho_m = 3.6e-5
    K_rho_sd_m = 2e-4

The priors only steer the choice among the poses the floor marks allow and the
operator-slip check (odohil/science/pose_selection.py); they never enter the
estimate.

What depends on the robot (its line speeds, its ``[robot]`` keys, its nominal
constants, whether its turns are exact) comes from its backend's
:class:`~odohil.science.robot_facts.RobotFacts`, handed to the parser as a
value (``facts``; the session's ``parse_description`` hands the registry's,
odohil/session/robots/registry.py); this module names no robot.
"""

from __future__ import annotations

import math
import tomllib
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt

from odohil import units
from odohil.errors import ParameterError, RobotDescriptionError
from odohil.science.diff_drive import DiffDriveGeometry
from odohil.science.limits import RANGES
from odohil.science.parameters import NOMAD150, PARAMETER_NAMES, ErrorParameters
from odohil.science.robot_facts import DRIVE_KEYS, RobotFacts

FloatArray = npt.NDArray[np.float64]

DEFAULT_TIMEOUT_S = 1.0
MAX_CROSS_PAIRS = 2
MIN_SCREW_SEPARATION_M = 0.01
"""Two screws closer than this (metres) count as coincident."""
MAX_FLOOR_M = 1000.0
"""Longest free floor a robot description may give, metres."""
MIN_SPREAD_RATIO = 0.1
"""Screws count as (near-)collinear when their spread across their best-fit line
is less than this fraction of their spread along it (ratio of the singular
values of the centred positions); the pose from such marks is ill-conditioned."""

_TOP_KEYS = ("robot", "screws", "measurement", "serial", "priors", "floor")
DEFAULT_PROTOCOL = "nomad150"
"""The robot protocol (driver backend) when ``[robot] protocol`` is absent."""
RECORDED_PROTOCOL = "recorded"
"""The protocol of a robot known only from its logs (no backend: docs/recording.md)."""
_COMMON_ROBOT_KEYS = ("protocol", "turns_exact")
"""``[robot]`` keys of every description; the others are the backend's
(``RobotFacts.robot_keys``), or, with no installed backend, these:"""
_ANY_ROBOT_KEYS = (*_COMMON_ROBOT_KEYS, *DRIVE_KEYS, "full_mode")
FactsLookup = Callable[[str], RobotFacts | None]
"""The facts of the backend of a protocol name (None: no such backend installed)."""
_DRIVE_RANGES = {
    "counts_per_rev": (1.0, 1e6),
    "wheel_diameter_m": (0.005, 2.0),
    "wheel_base_m": (0.02, 5.0),
}
"""Accepted ranges of a differential drive's kinematic constants (``[robot]``)."""
_FLOOR_KEYS = ("length_m",)
_PRIOR_KEYS = (
    "E_R_deg_per_m",
    "E_R_sd_deg_per_m",
    "E_T",
    "E_T_sd",
    "K_theta_deg2_per_m",
    "K_theta_sd_deg2_per_m",
    "K_rho_m",
    "K_rho_sd_m",
)
DEFAULT_PRIOR_SD_PAPER: tuple[float, float, float, float] = (0.5, 0.05, 0.05, 2e-4)
"""Default prior spreads (deg/m, 1, deg^2/m, m): 2.5 times |E_R|, 5 % on the
distance scale, 4 times K_theta and 5 times K_rho of the Nomad 150, so that a
robot several times worse than the paper's still lies within two of them."""
_MEASUREMENT_KEYS = ("sigma_m", "cross", "pose_sigma", "still_window_s")
_SERIAL_KEYS = ("port", "baud", "timeout_s")


@dataclass(frozen=True)
class Screw:
    """A marking screw on the robot's base.

    Attributes:
        name: the key in the ``[screws]`` table.
        x_m: position along the robot's forward axis, metres.
        y_m: position along the robot's left axis, metres.
    """

    name: str
    x_m: float
    y_m: float


@dataclass(frozen=True)
class RobotSettings:
    """Which robot this is (``[robot]``).

    Attributes:
        protocol: the driver backend's name in the ``odohil.robots``
            entry-point group (odohil/session/robots/registry.py).
    """

    protocol: str = DEFAULT_PROTOCOL
    drive: DiffDriveGeometry | None = None
    """A differential drive's counts per revolution, wheel diameter and wheel
    base (``counts_per_rev``, ``wheel_diameter_m``, ``wheel_base_m``; defaults:
    the backend's nominal constants, ``RobotFacts.drive``); None when neither
    the description nor the backend gives them (not a differential drive)."""
    full_mode: bool = False
    """``full_mode``: the Create 2 drives in the OI's Full mode (no safety stops)."""
    turns_exact: bool = True
    """``turns_exact``: in-place turns carry no error (the paper's synchronous
    drive). False for a differential drive: ``turn`` designs would fold the
    spins' errors into E_R and K_theta, so plans default to ``reverse``."""


@dataclass(frozen=True)
class SerialSettings:
    """How the driver reaches the robot.

    Attributes:
        port: device path or any pyserial URL; None when not configured.
        baud: line speed in baud (one of the backend's ``baud_rates``); None:
            the backend's default.
        timeout_s: the driver's reply timeout, s (default: the backend's,
            ``RobotFacts.reply_timeout_s``; checked against its
            ``reply_timeout_range_s``); handed to the backend only when given.
        given: the keys the file gave (the others are defaults), so that a
            command can say where each value in force came from.
    """

    port: str | None = None
    baud: int | None = None
    timeout_s: float = DEFAULT_TIMEOUT_S
    given: frozenset[str] = field(default=frozenset(), compare=False)


def _paper_to_si(values: tuple[float, float, float, float]) -> tuple[float, float, float, float]:
    e_r, e_t, k_theta, k_rho = (
        units.parameter_from_paper(name, value)
        for name, value in zip(PARAMETER_NAMES, values, strict=True)
    )
    return (e_r, e_t, k_theta, k_rho)


@dataclass(frozen=True)
class ParameterPriors:
    """A Gaussian belief in the four parameters before any trial (SI).

    Attributes:
        mean: the believed values (default: the paper's Nomad 150).
        sd: one standard deviation each, (rad/m, 1, rad^2/m, m), all positive.
        given: the description has a ``[priors]`` table (False: these are
            the defaults, a guess, and the slip check predicts the first
            trials, before there is an estimate, for any robot of
            odohil/science/pose_selection.py's ``UNKNOWN_ROBOT`` instead).
    """

    mean: ErrorParameters = NOMAD150
    sd: tuple[float, float, float, float] = _paper_to_si(DEFAULT_PRIOR_SD_PAPER)
    given: bool = False

    def __post_init__(self) -> None:
        for name, value in zip(_PRIOR_KEYS[1::2], self.sd, strict=True):
            if not math.isfinite(value) or value <= 0:
                raise RobotDescriptionError(
                    f"priors.{name} must be a positive number, got {value!r}"
                )

    def cov(self) -> FloatArray:
        """The 4x4 covariance (SI), diagonal."""
        return np.diag(np.square(np.array(self.sd, dtype=np.float64)))


@dataclass(frozen=True)
class RobotDescription:
    """A validated robot description (SI units).

    Attributes:
        screws: the marking screws, in file order (at least three, not collinear).
        sigma_m: standard deviation of one tape reading, metres.
        cross_pairs: (i, j) screw names, at most two: the distance from the start
            mark of screw i to the end mark of screw j is measured.
        serial: serial-line settings for the driver.
        priors: belief in the parameters before any trial (``[priors]``).
        floor_length_m: free floor along the robot's line of travel, metres
            (``[floor] length_m``); None when not given. No plan may need more.
        pose_sigma: standard deviations of one still pose taken by motion
            capture (``[measurement] pose_sigma``): x m, y m along the capture
            system's world axes, theta rad; None when not given (motion
            capture then refuses to start).
        robot: which robot this is (``[robot]``).
        still_window_s: how long motion capture collects the frames of one
            still pose, s (``[measurement] still_window_s``); None: the still
            window's default (odohil/session/measure/mocap/still.py, 0.5 s). A still
            pose is the median of the window's frames, so pose_sigma is the
            spread of still poses taken over this window.
    """

    screws: tuple[Screw, ...]
    sigma_m: float
    cross_pairs: tuple[tuple[str, str], ...] = ()
    serial: SerialSettings = field(default_factory=SerialSettings)
    priors: ParameterPriors = field(default_factory=ParameterPriors)
    floor_length_m: float | None = None
    pose_sigma: tuple[float, float, float] | None = None
    robot: RobotSettings = field(default_factory=RobotSettings)
    still_window_s: float | None = None

    def __post_init__(self) -> None:
        _check_screws(self.screws)
        if not math.isfinite(self.sigma_m) or self.sigma_m <= 0:
            raise RobotDescriptionError(
                f"measurement.sigma_m must be a positive number of metres, got {self.sigma_m!r}"
            )
        _in_range("sigma_m", "measurement.sigma_m", self.sigma_m)
        _check_cross_pairs(self.cross_pairs, tuple(s.name for s in self.screws))
        _check_serial(self.serial)
        if self.pose_sigma is not None:
            _check_pose_sigma(self.pose_sigma)
        if self.still_window_s is not None:
            _in_range("still_window_s", "measurement.still_window_s", self.still_window_s)
        floor = self.floor_length_m
        if floor is not None and (not math.isfinite(floor) or not 0 < floor <= MAX_FLOOR_M):
            raise RobotDescriptionError(
                f"floor.length_m must be a length in metres in (0, {MAX_FLOOR_M:g}], got {floor!r}"
            )

    @property
    def screw_names(self) -> tuple[str, ...]:
        """Screw names in file order."""
        return tuple(screw.name for screw in self.screws)

    def positions(self) -> FloatArray:
        """Screw positions in the robot frame, shape (n, 2), metres."""
        return np.array([[s.x_m, s.y_m] for s in self.screws], dtype=np.float64)

    def cross_indices(self) -> tuple[tuple[int, int], ...]:
        """The cross pairs as (i, j) indices into :attr:`screws`."""
        names = self.screw_names
        return tuple((names.index(i), names.index(j)) for i, j in self.cross_pairs)


def parse_robot_description(
    text: str, source: str = "robot description", facts: FactsLookup | None = None
) -> RobotDescription:
    """Parse and validate a robot description from TOML text.

    ``facts`` gives the backend's facts of the description's protocol
    (odohil/session/robots/registry.py ``parse_description`` passes the registry's);
    with them the description is checked against the robot: ``[serial] baud``
    one of its line speeds, only its ``[robot]`` keys, its nominal constants
    and ``turns_exact`` as defaults. Without (None, or no such backend): any
    positive baud, every ``[robot]`` key, no nominal constants, turns that
    carry error.

    Raises:
        RobotDescriptionError: the text is not TOML, or a key is unknown,
            missing, of the wrong type or out of range; the message names the
            key (prefixed by ``source``) and the problem.
    """
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise RobotDescriptionError(f"{source}: not valid TOML: {exc}") from exc
    try:
        return _from_mapping(data, facts)
    except RobotDescriptionError as exc:
        raise RobotDescriptionError(f"{source}: {exc}") from None


def _from_mapping(data: dict[str, Any], lookup: FactsLookup | None) -> RobotDescription:
    _reject_unknown(data, _TOP_KEYS, "")
    robot, facts = _robot(_table(data, "robot", required=False), lookup)
    screws_table = _table(data, "screws", required=True)
    screws = tuple(_screw(name, value, f"screws.{name}") for name, value in screws_table.items())
    measurement = _table(data, "measurement", required=True)
    _reject_unknown(measurement, _MEASUREMENT_KEYS, "measurement.")
    if "sigma_m" not in measurement:
        raise RobotDescriptionError("measurement.sigma_m is missing")
    sigma_m = _number(measurement["sigma_m"], "measurement.sigma_m")
    cross_pairs = _cross_pairs(measurement.get("cross", []))
    pose_sigma = _pose_sigma(measurement["pose_sigma"]) if "pose_sigma" in measurement else None
    window = measurement.get("still_window_s")
    still_window_s = None if window is None else _number(window, "measurement.still_window_s")
    serial_table = _table(data, "serial", required=False)
    _reject_unknown(serial_table, _SERIAL_KEYS, "serial.")
    serial = _serial(serial_table, facts)
    floor_table = _table(data, "floor", required=False)
    _reject_unknown(floor_table, _FLOOR_KEYS, "floor.")
    floor = floor_table.get("length_m")
    floor_m = None if floor is None else _number(floor, "floor.length_m")
    return RobotDescription(
        screws=screws,
        sigma_m=sigma_m,
        cross_pairs=cross_pairs,
        serial=serial,
        priors=_priors(_table(data, "priors", required=False), given="priors" in data),
        floor_length_m=floor_m,
        pose_sigma=pose_sigma,
        robot=robot,
        still_window_s=still_window_s,
    )


def _robot(
    table: dict[str, Any], lookup: FactsLookup | None
) -> tuple[RobotSettings, RobotFacts | None]:
    protocol = table.get("protocol", DEFAULT_PROTOCOL)
    if not isinstance(protocol, str) or not protocol.strip():
        raise RobotDescriptionError(
            f"robot.protocol must be a backend name like {DEFAULT_PROTOCOL!r}, got {protocol!r}"
        )
    protocol = protocol.strip()
    facts = None if lookup is None else lookup(protocol)
    known = _ANY_ROBOT_KEYS if facts is None else (*_COMMON_ROBOT_KEYS, *facts.robot_keys)
    hint = ""
    if "protocol" not in table and all(key in _ANY_ROBOT_KEYS for key in table):
        hint = (
            f" (without robot.protocol the robot is a {DEFAULT_PROTOCOL}); for a robot known "
            f'from its logs add protocol = "{RECORDED_PROTOCOL}" to [robot]'
        )
    _reject_unknown(table, known, "robot.", hint)
    nominal = None if facts is None else facts.drive
    constants: dict[str, float] = {}
    for key, (low, high) in _DRIVE_RANGES.items():
        if key not in table:
            if nominal is not None:
                constants[key] = getattr(nominal, key)
                if key == "wheel_diameter_m" and nominal.right_wheel_diameter_m is not None:
                    constants["right_wheel_diameter_m"] = nominal.right_wheel_diameter_m
            continue
        given = table[key]
        values = [given]
        if key == "wheel_diameter_m" and isinstance(given, list):
            if len(given) != 2:
                raise RobotDescriptionError(
                    f"robot.{key} must be one number or [left, right] in metres, got {given!r}"
                )
            values = given
        for index, item in enumerate(values):
            name = f"robot.{key}" if len(values) == 1 else f"robot.{key}[{index}]"
            value = _number(item, name)
            if not low <= value <= high:
                raise RobotDescriptionError(f"{name} must be in [{low:g}, {high:g}], got {value!r}")
            if index == 0:
                constants[key] = value
            else:
                constants["right_wheel_diameter_m"] = value
    drive = None
    if constants:
        missing = [key for key in DRIVE_KEYS if key not in constants]
        if missing:
            raise RobotDescriptionError(
                f"robot.{missing[0]} is missing: a differential drive needs "
                f"{', '.join('robot.' + k for k in DRIVE_KEYS)} (the {protocol} backend "
                "gives no nominal value)"
            )
        drive = DiffDriveGeometry(**constants)
    full_mode = table.get("full_mode", False)
    if not isinstance(full_mode, bool):
        raise RobotDescriptionError(f"robot.full_mode must be true or false, got {full_mode!r}")
    turns_exact = table.get("turns_exact", False if facts is None else facts.turns_exact)
    if not isinstance(turns_exact, bool):
        raise RobotDescriptionError(f"robot.turns_exact must be true or false, got {turns_exact!r}")
    settings = RobotSettings(
        protocol=protocol, drive=drive, full_mode=full_mode, turns_exact=turns_exact
    )
    return settings, facts


def _priors(table: dict[str, Any], given: bool) -> ParameterPriors:
    """``[priors]``; ``given``: the table is there, even empty (the paper's
    Nomad 150 with the default deviations, said of this robot)."""
    _reject_unknown(table, _PRIOR_KEYS, "priors.")
    default_mean = NOMAD150.to_paper_units()
    means = tuple(
        _number(table.get(key, default_mean[name]), f"priors.{key}")
        for key, name in zip(_PRIOR_KEYS[0::2], default_mean, strict=True)
    )
    sds = tuple(
        _number(table.get(key, default), f"priors.{key}")
        for key, default in zip(_PRIOR_KEYS[1::2], DEFAULT_PRIOR_SD_PAPER, strict=True)
    )
    for key, value in zip(_PRIOR_KEYS[1::2], sds, strict=True):
        if value <= 0:
            raise RobotDescriptionError(f"priors.{key} must be a positive number, got {value!r}")
    try:
        mean = ErrorParameters.from_paper_units(*means)
    except ParameterError as exc:
        raise RobotDescriptionError(f"priors: {exc}") from None
    return ParameterPriors(
        mean=mean, sd=_paper_to_si((sds[0], sds[1], sds[2], sds[3])), given=given
    )


def _reject_unknown(
    table: dict[str, Any], known: tuple[str, ...], prefix: str, hint: str = ""
) -> None:
    unknown = [key for key in table if key not in known]
    if unknown:
        listed = ", ".join(f"{prefix}{key}" for key in unknown)
        raise RobotDescriptionError(
            f"unknown key(s) {listed}; allowed here: {', '.join(prefix + k for k in known)}" + hint
        )


def _table(data: dict[str, Any], key: str, required: bool) -> dict[str, Any]:
    if key not in data:
        if required:
            raise RobotDescriptionError(f"the [{key}] table is missing")
        return {}
    value = data[key]
    if not isinstance(value, dict):
        raise RobotDescriptionError(f"{key} must be a table ([{key}]), got {value!r}")
    return value


def _number(value: Any, key: str) -> float:
    # bool is an int subclass in Python; `true` is not a length.
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise RobotDescriptionError(f"{key} must be a number, got {value!r}")
    result = float(value)
    if not math.isfinite(result):
        raise RobotDescriptionError(f"{key} must be a finite number, got {value!r}")
    return result


def _screw(name: str, value: Any, key: str) -> Screw:
    if not isinstance(value, list) or len(value) != 2:
        raise RobotDescriptionError(f"{key} must be [x, y] in metres, got {value!r}")
    return Screw(name, _number(value[0], f"{key}[0]"), _number(value[1], f"{key}[1]"))


def _cross_pairs(value: Any) -> tuple[tuple[str, str], ...]:
    key = "measurement.cross"
    if not isinstance(value, list):
        raise RobotDescriptionError(f"{key} must be a list of [start, end] screw names")
    pairs: list[tuple[str, str]] = []
    for index, pair in enumerate(value):
        if (
            not isinstance(pair, list)
            or len(pair) != 2
            or not all(isinstance(name, str) for name in pair)
        ):
            raise RobotDescriptionError(
                f'{key}[{index}] must be a pair of screw names like ["A", "B"], got {pair!r}'
            )
        pairs.append((pair[0], pair[1]))
    return tuple(pairs)


def _pose_sigma(value: Any) -> tuple[float, float, float]:
    key = "measurement.pose_sigma"
    if not isinstance(value, list) or len(value) != 3:
        raise RobotDescriptionError(
            f"{key} must be [sigma_x_m, sigma_y_m, sigma_theta_rad], got {value!r}"
        )
    x, y, theta = (_number(v, f"{key}[{i}]") for i, v in enumerate(value))
    return (x, y, theta)


def _check_pose_sigma(sigma: tuple[float, float, float]) -> None:
    key = "measurement.pose_sigma"
    _in_range("pose_sigma_m", f"{key}[0] (sigma_x_m)", sigma[0])
    _in_range("pose_sigma_m", f"{key}[1] (sigma_y_m)", sigma[1])
    _in_range("pose_sigma_rad", f"{key}[2] (sigma_theta_rad)", sigma[2])


def _serial(table: dict[str, Any], facts: RobotFacts | None) -> SerialSettings:
    port = table.get("port")
    if port is not None and (not isinstance(port, str) or not port):
        raise RobotDescriptionError(f"serial.port must be a non-empty string, got {port!r}")
    baud_value = table.get("baud", None if facts is None else facts.default_baud)
    if baud_value is not None and (isinstance(baud_value, bool) or not isinstance(baud_value, int)):
        raise RobotDescriptionError(f"serial.baud must be an integer, got {baud_value!r}")
    if facts is not None and baud_value is not None and not facts.speaks(baud_value):
        raise RobotDescriptionError(
            f"serial.baud must be one of {list(facts.baud_rates)} for {facts.name}, "
            f"got {baud_value!r}"
        )
    default_timeout = DEFAULT_TIMEOUT_S if facts is None else facts.reply_timeout_s
    timeout_s = _number(table.get("timeout_s", default_timeout), "serial.timeout_s")
    if facts is not None and "timeout_s" in table:
        try:
            facts.check_reply_timeout(timeout_s, "serial.timeout_s")
        except ParameterError as exc:
            raise RobotDescriptionError(str(exc)) from None
    return SerialSettings(port=port, baud=baud_value, timeout_s=timeout_s, given=frozenset(table))


def _check_screws(screws: tuple[Screw, ...]) -> None:
    if len(screws) < 3:
        raise RobotDescriptionError(
            f"screws: at least three screws are needed to fix a planar pose, got {len(screws)}"
        )
    names = [s.name for s in screws]
    for screw in screws:
        if not screw.name:
            raise RobotDescriptionError("screws: a screw needs a non-empty name")
        if not (math.isfinite(screw.x_m) and math.isfinite(screw.y_m)):
            raise RobotDescriptionError(f"screws.{screw.name} must be finite")
        _in_range("screw_m", f"screws.{screw.name} x", screw.x_m)
        _in_range("screw_m", f"screws.{screw.name} y", screw.y_m)
    if len(set(names)) != len(names):
        raise RobotDescriptionError(f"screws: names must be unique, got {names}")
    points = np.array([[s.x_m, s.y_m] for s in screws], dtype=np.float64)
    for i in range(len(screws)):
        for j in range(i + 1, len(screws)):
            gap = float(np.hypot(*(points[i] - points[j])))
            if gap < MIN_SCREW_SEPARATION_M:
                raise RobotDescriptionError(
                    f"screws.{names[i]} and screws.{names[j]} coincide ({gap:.4g} m apart; "
                    f"at least {MIN_SCREW_SEPARATION_M} m needed)"
                )
    spread = np.linalg.svd(points - points.mean(axis=0), compute_uv=False)
    if spread[1] < MIN_SPREAD_RATIO * spread[0]:
        raise RobotDescriptionError(
            "screws are (nearly) collinear: their spread across the line they lie on is "
            f"{spread[1] / spread[0]:.3g} of the spread along it (at least {MIN_SPREAD_RATIO} "
            "needed), so the floor marks cannot fix the heading"
        )


def _check_cross_pairs(pairs: tuple[tuple[str, str], ...], names: tuple[str, ...]) -> None:
    key = "measurement.cross"
    if len(pairs) > MAX_CROSS_PAIRS:
        raise RobotDescriptionError(
            f"{key}: at most {MAX_CROSS_PAIRS} cross distances are used, got {len(pairs)}"
        )
    for index, (start, end) in enumerate(pairs):
        for name in (start, end):
            if name not in names:
                raise RobotDescriptionError(
                    f"{key}[{index}] names unknown screw {name!r}; screws are {list(names)}"
                )
        if start == end:
            raise RobotDescriptionError(
                f"{key}[{index}] names screw {start!r} twice; a cross distance joins the start "
                "mark of one screw to the end mark of another"
            )
    if len(set(pairs)) != len(pairs):
        raise RobotDescriptionError(f"{key}: the same pair is listed twice: {list(pairs)}")


def _check_serial(serial: SerialSettings) -> None:
    if serial.baud is not None and serial.baud <= 0:
        raise RobotDescriptionError(f"serial.baud must be a positive integer, got {serial.baud!r}")
    if not math.isfinite(serial.timeout_s) or serial.timeout_s <= 0:
        raise RobotDescriptionError(
            f"serial.timeout_s must be a positive number of seconds, got {serial.timeout_s!r}"
        )
    _in_range("timeout_s", "serial.timeout_s", serial.timeout_s)


def _in_range(name: str, key: str, value: float) -> None:
    """RobotDescriptionError naming ``key`` unless ``value`` is in ``RANGES[name]``."""
    try:
        RANGES[name].check(key, value)
    except ParameterError as exc:
        raise RobotDescriptionError(str(exc)) from None
