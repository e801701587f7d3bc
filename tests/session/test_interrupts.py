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

import pytest

from odohil.session.wizard.interrupts import Interrupts

CHILD = """
import os, signal, sys, time
from tests.session.helpers import FAST, fake_robot
from odohil.session.wizard.interrupts import Interrupts

interrupts = Interrupts(lambda text: os.write(2, text.encode()), 130, 4, "may still move")
with interrupts.installed(), fake_robot(FAST) as (robot, truth):
    interrupts.in_motion = True
    if sys.argv[1] == "robot":
        interrupts.robot = robot
    os.kill(os.getpid(), signal.SIGINT)
    os.kill(os.getpid(), signal.SIGINT)
    time.sleep(5)
sys.exit(0)
"""


def test_a_ctrl_c_during_a_motion_waits_for_the_next_sample() -> None:
    said: list[str] = []
    interrupts = Interrupts(said.append, 130, 4, "may still move")
    with interrupts.installed():
        interrupts.in_motion = True
        os.kill(os.getpid(), signal.SIGINT)
        assert interrupts.pending
        assert said == ["\nCtrl-C: stopping the robot...\n"]
        with pytest.raises(KeyboardInterrupt):
            interrupts.check()
        interrupts.check()  # raised once


def test_a_ctrl_c_at_a_prompt_is_raised_at_once() -> None:
    interrupts = Interrupts([].append, 130, 4, "may still move")
    with interrupts.installed(), pytest.raises(KeyboardInterrupt):
        os.kill(os.getpid(), signal.SIGINT)


def test_the_policy_gives_back_the_handler_it_found() -> None:
    """Before: ``install`` took SIGINT for good; the in-process wizard (a test,
    a library caller) left its worker with the policy's handler, and a later
    Ctrl-C there met it (tests/conftest.py now checks every test)."""
    found = signal.getsignal(signal.SIGINT)
    policy = Interrupts([].append, 130, 4, "")
    with policy.installed():
        assert signal.getsignal(signal.SIGINT) == policy._handler
    assert signal.getsignal(signal.SIGINT) is found
    with pytest.raises(KeyboardInterrupt), policy.installed():
        os.kill(os.getpid(), signal.SIGINT)  # the policy's Ctrl-C at a prompt
    assert signal.getsignal(signal.SIGINT) is found


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
