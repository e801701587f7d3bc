"""How every backend stops its robot: one implementation, used by each
robot's connection (odohil/driver/nomad/robot.py, odohil/driver/create2/robot.py).

- :func:`stop_and_confirm`: send the stop, then read until the robot reports
  standing still, within a bound; StopUnconfirmedError (saying why: line
  closed or cut, no or bad replies, still moving) when it does not;
- :func:`settle`: bring a robot to rest: nothing sent when a reading shows it
  standing still, else :func:`stop_and_confirm`;
- :func:`stop_on_failure`: a block whose any exception (Ctrl-C too) stops the
  robot, best effort, before it propagates.

The backend hands in what differs: how to send the stop, how to read, and
what "moving" means for a reading of its robot.
"""

from __future__ import annotations

import contextlib
import math
import time
from collections.abc import Callable, Iterator
from typing import TypeVar

from odohil.errors import (
    DisconnectedError,
    OdohilError,
    ParameterError,
    StopUnconfirmedError,
)

Reading = TypeVar("Reading")
"""A backend's reading of its robot (an encoder sample, an odometry sample)."""


def check_timeout(timeout_s: float) -> float:
    """``timeout_s`` if finite and >= 0, else ParameterError."""
    if not math.isfinite(timeout_s) or timeout_s < 0:
        raise ParameterError(f"timeout must be finite and >= 0 s, got {timeout_s!r}")
    return timeout_s


def stop_and_confirm(
    timeout_s: float,
    *,
    stop: Callable[[float], Reading],
    read: Callable[[float], Reading],
    moving: Callable[[Reading], bool],
    where: Callable[[Reading], str],
    closed: Callable[[], bool],
    poll_s: float = 0.0,
    still_readings: int = 1,
    names: tuple[str, str] = ("the stop", "a reading"),
) -> Reading:
    """Stop the robot and wait until it reports standing still.

    ``stop(left_s)`` sends the stop and returns a reading (the Nomad's ``st``
    answers with its state), ``read(left_s)`` takes one more; each gets the
    time left, s. A stop that fails (OdohilError) is sent again while time is
    left; once one went out, readings follow. Nothing is asked after the line
    is closed or cut (DisconnectedError).

    Args:
        timeout_s: the whole bound, s (finite, >= 0).
        moving: whether a reading shows the robot moving.
        where: a reading's pose for messages.
        closed: whether the line is closed.
        poll_s: pause between two readings, s.
        still_readings: readings in a row that must show it still.
        names: how messages name a failed stop and a failed reading.

    Returns:
        The reading that confirmed the stop.

    Raises:
        ParameterError: a timeout that is not finite and >= 0.
        StopUnconfirmedError: the robot did not report that it stopped within
            ``timeout_s`` (the message says why).
    """
    check_timeout(timeout_s)
    deadline = time.monotonic() + timeout_s
    step, name = stop, names[0]
    problem = "no time to ask"
    still = 0

    def pause() -> None:
        time.sleep(min(poll_s, max(0.0, deadline - time.monotonic())))

    while not closed():
        left = deadline - time.monotonic()
        if left <= 0:
            break
        try:
            reading = step(left)
        except DisconnectedError as exc:
            problem = f"the line is cut ({exc})"
            break
        except OdohilError as exc:
            problem = f"{name} failed: {exc}"
            pause()
            continue
        step, name = read, names[1]
        if moving(reading):
            still = 0
            problem = f"still moving at {where(reading)}"
        else:
            still += 1
            if still >= still_readings:
                return reading
        pause()
    if closed() and problem == "no time to ask":
        problem = "the line is closed"
    raise StopUnconfirmedError(
        f"the robot did not report that it stopped within {timeout_s:g} s: {problem}"
    )


def settle(
    timeout_s: float,
    *,
    read: Callable[[], Reading],
    moving: Callable[[Reading], bool],
    confirm: Callable[[float], Reading],
) -> Reading:
    """Bring the robot to rest within ``timeout_s``: ``read()`` once; a
    reading that shows it standing still is returned with nothing sent, else
    ``confirm(timeout_s)`` (the backend's :func:`stop_and_confirm`)."""
    check_timeout(timeout_s)
    reading = read()
    if not moving(reading):
        return reading
    return confirm(timeout_s)


@contextlib.contextmanager
def stop_on_failure(
    stop: Callable[[], object], when: Callable[[], bool] | None = None
) -> Iterator[None]:
    """Within: any exception (and Ctrl-C) calls ``stop()`` (best effort: its
    own OdohilError is dropped) before it propagates; with ``when``, only
    while ``when()`` is true (e.g. the robot was told to move)."""
    try:
        yield
    except BaseException:
        if when is None or when():
            with contextlib.suppress(OdohilError):
                stop()
        raise
