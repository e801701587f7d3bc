"""pyserial URL handler ``fakecreate2://``: the fake iRobot Create 2 in process.

URL: ``fakecreate2://?seed=1&time_scale=10&fault=cliff@0.5&E_R=-0.35&E_T=-0.015&K_theta=0.02&K_rho=5e-5&turn_scale=0.012&spin_k=2e-4&encoder_origin=65000&mode_offset=1&angle_bug=1&pacing=1&max_gap_ms=15&baud=115200&mode_change_ms=50&passive_sleep_s=300``
(every option optional; ``fault`` may repeat; E_R, E_T, K_theta, K_rho in the
paper's units; ``baud`` is the robot's line rate (default 115200): a port
opened, or later set, at another rate reads garbage and is not understood
(fakes/create2/line.py); ``mode_change_ms``: how long Safe and Full take to
take effect; ``passive_sleep_s``: simulated seconds before Passive sleeps, 0
never; pacing off unless ``pacing=1``, then at the port's baud rate;
``max_gap_ms``: the fake's clock skips any gap between two host calls longer
than this, fakes/create2/clock.py, so a descheduled host cannot make a leg
drive on; default: wall time; ``skip_waits=1``: a read that waits for the
robot's next frame or reply moves the fake's clock to it instead of sleeping
(with ``max_gap_ms``, or alone: then no gap is cut), so the fake runs as fast
as the host computes; the host sees the same frames at the same simulated
times).
Opened with ``serial.serial_for_url`` once :mod:`fakes` is imported.

The port is the fake Nomad's in-process port (fakes/protocol_fakerobot.py)
carrying a :class:`~fakes.create2.engine.Create2Engine`; no thread, the robot
runs whenever the port is used.
"""

from __future__ import annotations

import math
import time
import urllib.parse
from collections.abc import Callable
from typing import Any, cast

from serial.serialutil import SerialException

from fakes import url_options
from fakes.create2.clock import LagAbsorbingClock
from fakes.create2.config import CREATE2_TRUTH, build_config
from fakes.create2.engine import Create2Engine
from fakes.create2.truth import Create2Truth
from fakes.nomad.engine import NomadEngine
from fakes.protocol_fakerobot import Serial as FakeNomadSerial
from odohil.errors import OdohilError
from odohil.science.parameters import ErrorParameters

_PAPER = ("E_R", "E_T", "K_theta", "K_rho")
OPTIONS = (
    "seed", "time_scale", "fault", "pacing", *_PAPER, "turn_scale", "spin_k",
    "encoder_origin", "mode_offset", "angle_bug", "max_gap_ms", "skip_waits", "baud",
    "mode_change_ms", "passive_sleep_s",
)  # fmt: skip
"""The URL's options (a bad one: PortOptionError, fakes/url_options.py)."""


class Serial(FakeNomadSerial):
    """A serial port with a fake Create 2 at the other end."""

    def truth(self) -> Create2Truth:  # type: ignore[override]
        """The robot's true state (a real robot has no such thing)."""
        return self._create2().truth()

    def event(self, name: str) -> Create2Truth:
        """Test hook: inject a safety event now; the state after it."""
        engine = self._create2()
        engine.event(name)
        return engine.truth()

    def _create2(self) -> Create2Engine:
        return cast(Create2Engine, self._engine(check_cut=False))

    def _reconfigure_port(self) -> None:
        super()._reconfigure_port()
        if self.is_open and self.engine is not None:
            cast(Create2Engine, self.engine).host_baud = self._baudrate

    def _engine_from_url(self, url: str) -> NomadEngine:
        parts = urllib.parse.urlsplit(url)
        if parts.scheme != "fakecreate2":
            raise SerialException(f"expected fakecreate2://?options, got {url!r}")
        options = urllib.parse.parse_qs(parts.query, keep_blank_values=True)
        paper = CREATE2_TRUTH.to_paper_units()
        kwargs: dict[str, Any] = {}
        faults: list[str] = []
        self._pacing = False
        max_gap_s: float | None = None
        skip_waits = False
        try:
            for key, values in options.items():
                value = values[-1]
                if key == "seed":
                    kwargs["seed"] = url_options.integer(key, value)
                elif key in ("time_scale", "turn_scale", "spin_k"):
                    kwargs[key] = url_options.number(key, value)
                elif key in ("encoder_origin", "mode_offset", "baud"):
                    kwargs[key] = url_options.integer(key, value)
                elif key == "mode_change_ms":
                    kwargs["mode_change_s"] = url_options.number(key, value) / 1000.0
                elif key == "passive_sleep_s":
                    kwargs[key] = url_options.number(key, value) or None
                elif key == "angle_bug":
                    kwargs["angle_bug"] = value not in ("", "0", "false", "no")
                elif key == "fault":
                    faults.extend(values)
                elif key == "max_gap_ms":
                    max_gap_s = url_options.number(key, value) / 1000.0
                elif key == "skip_waits":
                    skip_waits = value not in ("", "0", "false", "no")
                elif key == "pacing":
                    self._pacing = value not in ("", "0", "false", "no")
                elif key in _PAPER:
                    paper[key] = url_options.number(key, value)
                else:
                    raise url_options.unknown(key, OPTIONS)
            params = ErrorParameters.from_paper_units(*(paper[k] for k in _PAPER))
            config = build_config(params=params, faults=faults, **kwargs)
            clock: Callable[[], float] = time.monotonic
            if max_gap_s is not None or skip_waits:
                bounded = LagAbsorbingClock(math.inf if max_gap_s is None else max_gap_s)
                self._skip = bounded.skip if skip_waits else None
                clock = bounded
        except (ValueError, OdohilError) as exc:
            raise url_options.bad_url("fakecreate2", url, exc) from exc
        engine = Create2Engine(config, clock)
        engine.host_baud = self._baudrate
        return cast(NomadEngine, engine)


__all__ = ["Serial"]
