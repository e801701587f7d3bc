"""The interactive session's Ctrl-C policy (odohil/session/wizard/interrupts.py).

The first Ctrl-C during a motion is deferred to the next encoder sample, in
process; the second Ctrl-C ends the process at once, so that is checked in a
child process (the process is the point): 130 when the robot (the in-process
fake, fakerobot://) confirmed its stop, 4 when there is no robot to confirm it.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from collections.abc import Iterator

import pytest

from odohil.session.wizard.interrupts import Interrupts

CHILD = """
import os, signal, sys, time
from tests.session.helpers import FAST, fake_robot
from odohil.session.wizard.interrupts import Interrupts

interrupts = Interrupts(lambda text: os.write(2, text.encode()), 130, 4, "may still move")
interrupts.install()
interrupts.in_motion = True
with fake_robot(FAST) as (robot, truth):
    if sys.argv[1] == "robot":
        interrupts.robot = robot
    os.kill(os.getpid(), signal.SIGINT)
    os.kill(os.getpid(), signal.SIGINT)
    time.sleep(5)
sys.exit(0)
"""


@pytest.fixture
def sigint() -> Iterator[None]:
    previous = signal.getsignal(signal.SIGINT)
    yield
    signal.signal(signal.SIGINT, previous)


def test_a_ctrl_c_during_a_motion_waits_for_the_next_sample(sigint: None) -> None:
    said: list[str] = []
    interrupts = Interrupts(said.append, 130, 4, "may still move")
    interrupts.install()
    interrupts.in_motion = True
    os.kill(os.getpid(), signal.SIGINT)
    assert interrupts.pending
    assert said == ["\nCtrl-C: stopping the robot...\n"]
    with pytest.raises(KeyboardInterrupt):
        interrupts.check()
    interrupts.check()  # raised once


def test_a_ctrl_c_at_a_prompt_is_raised_at_once(sigint: None) -> None:
    interrupts = Interrupts([].append, 130, 4, "may still move")
    interrupts.install()
    with pytest.raises(KeyboardInterrupt):
        os.kill(os.getpid(), signal.SIGINT)


@pytest.mark.parametrize(("robot", "status", "said"), [
    ("robot", 130, "robot stopped (it reported standing still)"),
    ("none", 4, "WARNING: may still move"),
])  # fmt: skip
def test_a_second_ctrl_c_stops_and_exits_at_once(robot: str, status: int, said: str) -> None:
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}
    done = subprocess.run(
        [sys.executable, "-c", CHILD, robot], capture_output=True, text=True, timeout=60, env=env
    )
    assert done.returncode == status, done.stderr
    assert said in done.stderr
