"""pyserial URL handler ``fakerobot://``: the fake Nomad 150 in process.

URL: ``fakerobot://?seed=1&time_scale=50&fault=drop:gs@2&E_R=-0.2&E_T=-0.02&K_theta=0.012&K_rho=3.6e-5&pacing=1``
(every option optional; ``fault`` may repeat; parameters in the paper's units,
default Nomad 150 values; pacing off unless ``pacing=1``, then at the port's
baud rate). Opened with ``serial.serial_for_url`` once :mod:`fakes` is imported.

There is no thread: the robot runs whenever the port is used (read, write,
``in_waiting``, :meth:`Serial.truth`), on its own clock, so time passes between
calls exactly as it would for a real robot.
"""

from __future__ import annotations

import time
import urllib.parse
from collections.abc import Callable
from typing import Any

import serial
from serial.serialutil import PortNotOpenError, SerialBase, SerialException

from fakes import url_options
from fakes.nomad.config import build_config
from fakes.nomad.engine import Disconnect, NomadEngine
from fakes.nomad.pacing import LinePacer
from fakes.nomad.truth import TruthSnapshot
from odohil.errors import OdohilError
from odohil.science.parameters import NOMAD150

POLL_S = 0.002
"""Longest sleep while a read waits, wall s."""

_FLOAT_OPTIONS = {
    "E_R": "e_r_deg_per_m",
    "E_T": "e_t",
    "K_theta": "k_theta_deg2_per_m",
    "K_rho": "k_rho_m",
}
OPTIONS = ("seed", "time_scale", "fault", "pacing", *_FLOAT_OPTIONS)
"""The URL's options (a bad one: PortOptionError, fakes/url_options.py)."""


class Serial(SerialBase):  # type: ignore[misc]
    """A serial port with a fake Nomad 150 at the other end."""

    is_open: bool

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        self.engine: NomadEngine | None = None
        self._rx = bytearray()
        self._pacer = LinePacer(None)
        self._pacing = False
        self._cut = False
        self._skip: Callable[[float], None] | None = None
        """Moves the robot's clock forward (set by a subclass whose URL asks
        for it): a read that waits for the robot's next write jumps to it."""
        super().__init__(*args, **kwargs)

    # ---- SerialBase API --------------------------------------------------------
    def open(self) -> None:
        """Create the robot from the URL."""
        if self.is_open:
            raise SerialException("Port is already open.")
        if self._port is None:
            raise SerialException("Port must be configured before it can be used.")
        self.engine = self._engine_from_url(self.port)
        self._rx.clear()
        self._cut = False
        self._pacer = LinePacer(self._baudrate if self._pacing else None)
        self.is_open = True

    def close(self) -> None:
        """Close the port (the robot is discarded)."""
        self.is_open = False
        super().close()

    def _reconfigure_port(self) -> None:
        if self.is_open:
            self._pacer = LinePacer(self._baudrate if self._pacing else None)

    @property
    def in_waiting(self) -> int:
        """Bytes received and not yet read."""
        self._pump()
        return len(self._rx)

    @property
    def idle(self) -> bool:
        """True when no byte is on its way: nothing queued on the line (pacing)
        and nothing scheduled by the robot (a reply due later, a stray or late
        packet, line noise). The host's quiet wait before a request ends at once
        then (odohil/driver/port.py's ``vouches_idle``): it waits for bytes in
        flight, and this peer knows there are none."""
        self._pump()
        return (
            not self._rx and self._pacer.pending == 0 and self._engine().next_output_wall() is None
        )

    listens_at_open = True
    """The robot in this process listens as soon as the port is open (a real
    Create 2 is given its wait after open; odohil/driver/port.py)."""

    def read(self, size: int = 1) -> bytes:
        """Up to ``size`` bytes, waiting at most the port timeout (pyserial semantics)."""
        deadline = None if self._timeout is None else time.monotonic() + self._timeout
        while True:
            self._pump()
            if len(self._rx) >= size:
                break
            now = time.monotonic()
            if deadline is not None and now >= deadline:
                break
            wait = POLL_S
            engine = self._engine()
            due = engine.next_output_wall()  # on the engine's clock
            to_due = None if due is None else max(0.0, due - engine.clock())
            if to_due is not None:
                wait = min(wait, to_due)
            release = self._pacer.next_release()
            if release is not None:
                wait = min(wait, max(0.0, release - now))
            if deadline is not None:
                wait = min(wait, deadline - now)
            if self._skip is not None and to_due is not None:
                skipped = self._skip_to(to_due, now, deadline)
                if skipped == to_due:
                    continue  # the robot's write is due now
                if skipped > 0.0:
                    break  # the read's timeout passed on the robot's clock
            time.sleep(wait)
        data = bytes(self._rx[:size])
        del self._rx[:size]
        return data

    def _skip_to(self, to_due: float, now: float, deadline: float | None) -> float:
        """Instead of sleeping, move the robot's clock forward: ``to_due`` s
        to its next write, or only to the read's deadline when that comes
        first (the read then times out as it would have); 0 (no jump) when a
        line release comes first (pacing runs on the wall clock). The seconds
        jumped."""
        assert self._skip is not None
        step = to_due if deadline is None else max(0.0, min(to_due, deadline - now))
        release = self._pacer.next_release()
        if step <= 0.0 or (release is not None and release - now < step):
            return 0.0
        self._skip(step)
        return step

    def write(self, data: bytes | bytearray | memoryview) -> int:
        """Send ``data`` to the robot."""
        self._pump()
        payload = bytes(data)
        self._engine().receive(payload)
        return len(payload)

    def reset_input_buffer(self) -> None:
        """Discard what was received and not read."""
        self._pump()
        self._rx.clear()

    def reset_output_buffer(self) -> None:
        """Nothing is ever buffered on the way out."""
        self._check_open()

    @property
    def out_waiting(self) -> int:
        """Always 0: writes reach the robot at once."""
        self._check_open()
        return 0

    def _update_break_state(self) -> None:
        pass

    def _update_rts_state(self) -> None:
        pass

    def _update_dtr_state(self) -> None:
        pass

    @property
    def cts(self) -> bool:
        """Always True."""
        return True

    @property
    def dsr(self) -> bool:
        """Always True."""
        return True

    @property
    def ri(self) -> bool:
        """Always False."""
        return False

    @property
    def cd(self) -> bool:
        """Always True."""
        return True

    # ---- the side channel --------------------------------------------------------
    def truth(self) -> TruthSnapshot:
        """The robot's true pose and logs (a real robot has no such thing)."""
        return self._engine(check_cut=False).truth()

    # ---- internals ----------------------------------------------------------------
    def _check_open(self) -> None:
        if not self.is_open:
            raise PortNotOpenError()

    def _engine(self, check_cut: bool = True) -> NomadEngine:
        self._check_open()
        if check_cut and self._cut:
            raise SerialException("device disconnected (fake robot: fault disconnect)")
        assert self.engine is not None
        return self.engine

    def _pump(self) -> None:
        engine = self._engine()
        now = time.monotonic()
        for item in engine.take_output(engine.clock()):  # due on the engine's clock
            if isinstance(item, Disconnect):
                self._cut = True
                self._rx.clear()
                self._pacer.clear()
                raise SerialException("device disconnected (fake robot: fault disconnect)")
            self._pacer.push(item, now)
        self._rx += self._pacer.release(now)

    def _engine_from_url(self, url: str) -> NomadEngine:
        parts = urllib.parse.urlsplit(url)
        if parts.scheme != "fakerobot":
            raise SerialException(f"expected fakerobot://?options, got {url!r}")
        options = urllib.parse.parse_qs(parts.query, keep_blank_values=True)
        paper = NOMAD150.to_paper_units()
        kwargs: dict[str, float] = {_FLOAT_OPTIONS[k]: paper[k] for k in _FLOAT_OPTIONS}
        seed: int | None = None
        time_scale = 1.0
        faults: list[str] = []
        self._pacing = False
        try:
            for key, values in options.items():
                value = values[-1]
                if key == "seed":
                    seed = url_options.integer(key, value)
                elif key == "time_scale":
                    time_scale = url_options.number(key, value)
                elif key == "fault":
                    faults.extend(values)
                elif key == "pacing":
                    self._pacing = value not in ("", "0", "false", "no")
                elif key in _FLOAT_OPTIONS:
                    kwargs[_FLOAT_OPTIONS[key]] = url_options.number(key, value)
                else:
                    raise url_options.unknown(key, OPTIONS)
            config = build_config(seed=seed, time_scale=time_scale, faults=faults, **kwargs)
        except (ValueError, OdohilError) as exc:
            raise url_options.bad_url("fakerobot", url, exc) from exc
        return NomadEngine(config)


__all__ = ["Serial", "serial"]
