"""The real ``odohil wizard`` in a pseudo-terminal against the fake robot process.

A second session: a 10 mm typo that the consistency test cannot see is caught
by the slip check, which names the distance; re-entering it alone completes
the trial.

One session of three trials: bad inputs and an inconsistent set are refused
with their reasons, Ctrl-C during the third motion stops the robot, journals
and exits 130, and a second wizard on the same session completes it with
exactly three trials. The distances typed are the forward model of the fake's
true pose change (its truth side channel).
"""

from __future__ import annotations

import math
import os
import re
import sys
import time
from pathlib import Path

import pexpect
import pytest

from fakes.nomad.process import EmulatorProcess
from fakes.nomad.truth import TruthClient
from odohil.errors import InconsistentMeasurementError
from odohil.science.floor_marks import (
    MarkDistances,
    distance_labels,
    marks_from_pose,
    solve_marks,
)
from odohil.science.robot_description import parse_robot_description
from odohil.session.journal import events as ev
from odohil.session.journal.file import journal_path, read_journal
from odohil.session.journal.state import replay
from odohil.session.measure.tape.records import Measurement, Remeasured
from odohil.session.measure.truth import relative_true_pose
from tests import forked
from tests.session.helpers import FINE_TAPE_ROBOT_TOML as ROBOT_TOML

DESCRIPTION = parse_robot_description(ROBOT_TOML)
LABELS = distance_labels(DESCRIPTION)
TIMEOUT_S = 90
ORIGIN = (0.0, 0.0, 0.0)
LOG = Path(os.environ["WIZARD_TEST_LOG"]) if os.environ.get("WIZARD_TEST_LOG") else None
FAST = "400"
"""The emulator's time scale where no keystroke must land during a motion (the typo,
the squares, Ctrl-C at a distance prompt): the motions are not the check. The fake
draws its errors per segment of distance, not per tick, so the trials are the same
at any scale; the Ctrl-C cases mid-motion keep time scale 8."""


def _env() -> dict[str, str]:
    env = dict(os.environ)
    env.update({"NO_COLOR": "1", "COLUMNS": "250", "LINES": "50", "TERM": "xterm"})
    return env


def _spawn(args: list[str]) -> forked.PtyForked:
    """``odohil wizard ARGS`` on a pseudo-terminal of its own: a real process
    forked from a server that imported odohil once (tests/forked.py), without
    the interpreter's start and the imports of a console process."""
    return forked.spawn(
        ["wizard", *args],
        env=_env(),
        dimensions=(50, 250),
        timeout=TIMEOUT_S,
        logfile=LOG.open("a") if LOG else None,
    )


def _console(args: list[str]) -> pexpect.spawn:
    """``python -m odohil wizard ARGS`` as a console process on a pseudo-terminal:
    the console script's own start (only the wizard's command imported), which
    :func:`test_the_wizard_connects_with_robot_toml_serial_and_says_so` keeps."""
    return pexpect.spawn(
        sys.executable,
        ["-m", "odohil", "wizard", *args],
        env=_env(),
        encoding="utf-8",
        timeout=TIMEOUT_S,
        dimensions=(50, 250),
        logfile=LOG.open("a") if LOG else None,
    )


def _pose(truth: TruthClient) -> tuple[float, float, float]:
    snap = truth.snapshot()
    return (snap.true_x_m, snap.true_y_m, snap.true_theta_rad)


def _prompt(index: int) -> str:
    return re.escape(f"{LABELS[index]}, metres (")


def _answer(child: forked.PtyForked, text: str, then: str) -> None:
    """Type ``text``; confirm it if the wizard asks; wait for ``then``."""
    child.sendline(text)
    while child.expect([then, "type the same value again"]) == 1:
        child.sendline(text)


def _marks(child: forked.PtyForked, truth: TruthClient, asked: bool = False) -> list[float]:
    """Start marks, motion, end marks; the exact distances of the true pose change
    (``asked``: the start-marks prompt was already seen)."""
    if not asked:
        child.expect("Mark the floor at the 3 screws")
    start = _pose(truth)
    child.sendline("")
    child.expect(r"end marks\), then press Enter")
    end = _pose(truth)
    child.sendline("")
    change = relative_true_pose(start, end, 0.0)
    return [float(v) for v in marks_from_pose(DESCRIPTION, change).as_array()]


def _type_all(child: forked.PtyForked, values: list[float], done: str, digits: str = "") -> None:
    """Type every distance (``repr``, then ``digits`` more than a float holds)."""
    for i, value in enumerate(values):
        then = _prompt(i + 1) if i + 1 < len(values) else done
        _answer(child, repr(value) + digits, then)


def _refused(child: forked.PtyForked, text: str, reason: str) -> None:
    child.sendline(text)
    child.expect(reason)
    child.expect(_prompt(0))


def test_three_trial_session_with_bad_inputs_interrupt_and_resume(tmp_path: Path) -> None:
    robot = tmp_path / "robot.toml"
    robot.write_text(ROBOT_TOML)
    folder = tmp_path / "session"
    args = ["--seed", "21", "--time-scale", "8", "--no-pacing"]
    with EmulatorProcess(args, use_cli=True) as emu, TruthClient(emu.truth_socket) as truth:
        plan = "k=1,l=1,n=3"
        child = _spawn(["--port", emu.device, "--robot", str(robot), "--plan", plan,
                        "--session", str(folder)])  # fmt: skip
        # the robot answers before the session is written (nothing written before pre-flight)
        for check in ("robot description", "plan feasible", "robot answers", "session"):
            child.expect(r"\[ok\]\s+(\x1b\[[0-9;]*m)*" + re.escape(check))

        # Trial 1: every kind of bad input, then the true distances (one in mm).
        values = _marks(child, truth)
        child.expect(_prompt(0))
        _refused(child, "abc", "is not a number of metres")
        _refused(child, "-0.01", "cannot be negative")
        _refused(child, "nan", "is not a finite number")
        _refused(child, "1000", "is implausible")
        _answer(child, f"{values[0] * 1000!r} mm", _prompt(1))
        _type_all_from(child, values, 1, "Trial 1 solved")
        child.expect("No estimate yet")

        # Trial 2: a set no rigid motion explains (cross distance 2 off by 5 cm).
        values = _marks(child, truth)
        child.expect(_prompt(0))
        wrong = list(values)
        wrong[4] += 0.05
        _type_all(child, wrong, "fit no rigid motion")
        child.expect(re.escape(LABELS[4]))  # the suspect is named
        # before: every distance was asked again; now only those the rejection names
        child.expect(r"Measure again only ")
        asked = _retype_asked(child, values, "Trial 2 solved")
        assert 4 in asked, asked
        assert len(asked) < len(values), asked
        for name in (
            "phi1 deg",
            "Estimate after 2 trials",
            "E_R",
            "deg/m",
            "E_T",
            "K_theta",
            "deg^2/m",
            "K_rho",
        ):
            child.expect(re.escape(name))
        child.expect("more trials? reach(es)? the target|Target precision reached")

        # Trial 3: Ctrl-C during the motion.
        child.expect("Mark the floor at the 3 screws")
        child.sendline("")
        child.expect("driving k=1")
        child.sendintr()
        child.expect(r"Interrupted\S* \(Ctrl-C\)")
        child.expect("robot stopped")  # the robot reported it
        child.expect("session journaled")
        child.expect(pexpect.EOF)
        advice = " ".join(str(child.before).split())
        assert "odohil wizard --session" in advice, advice  # only what works:
        assert "odohil resume" not in advice, advice  # resume refuses wizard sessions
        child.close()
        assert child.exitstatus == 130
        assert not truth.snapshot().moving
        time.sleep(0.3)
        assert not truth.snapshot().moving
        kinds = [r.kind for r in read_journal(folder).records]
        assert kinds[-2:] == [ev.VOID, ev.STOPPED]
        assert kinds.count(ev.SOLVED) == 2

        # Resume: the wizard again on the same session redoes trial 3.
        child = _spawn(["--port", emu.device, "--session", str(folder)])
        child.expect(re.escape("resuming"))
        child.expect("heading=")
        # Ctrl-C right after the motion began: the robot may already be off the start
        asked = child.expect(["Put the robot back", "Mark the floor at the 3 screws"]) == 1
        if not asked:
            child.sendline("")
            child.expect("Encoders set to the trial's start")
        values = _marks(child, truth, asked)
        child.expect(_prompt(0))
        _type_all(child, values, "Trial 3 solved")
        child.expect(r"Session complete:\S* 3 trials")
        child.expect("verdict: DOUBTFUL")  # 3 trials: below the planner's minimum a design
        child.expect(pexpect.EOF)
        child.close()
        assert child.exitstatus == 3

    state = replay(read_journal(folder).records)
    assert state.finished
    assert [t.trial for t in state.completed] == [1, 2, 3]
    assert [t.attempt for t in state.completed] == [1, 1, 2]
    assert state.voided == 1


def _retype_asked(child: forked.PtyForked, values: list[float], done: str) -> list[int]:
    """Answer whichever distances are asked for (the true ones) until ``done``;
    the indices asked, in order."""
    asked: list[int] = []
    patterns = [_prompt(i) for i in range(len(values))] + [done]
    while (i := child.expect(patterns)) < len(values):
        asked.append(i)
        child.sendline(repr(values[i]))
    return asked


def _type_all_from(child: forked.PtyForked, values: list[float], first: int, done: str) -> None:
    for i in range(first, len(values)):
        then = _prompt(i + 1) if i + 1 < len(values) else done
        _answer(child, repr(values[i]), then)


def _absorbed_typo(values: list[float]) -> tuple[int, float]:
    """The 10 mm typo (distance index, typed value) that the consistency test
    cannot see and that puts the solved heading the most standard deviations
    from the truth (``values`` are the exact distances): the dangerous kind."""
    n = len(DESCRIPTION.screws)
    exact = solve_marks(DESCRIPTION, MarkDistances(tuple(values[:n]), tuple(values[n:])), ORIGIN)
    best: tuple[float, int, float] | None = None
    for index in range(len(values)):
        for sign in (1.0, -1.0):
            typed = list(values)
            typed[index] += sign * 0.010
            if typed[index] < 0:
                continue
            marks = MarkDistances(tuple(typed[:n]), tuple(typed[n:]))
            try:
                solved = solve_marks(DESCRIPTION, marks, ORIGIN)
            except InconsistentMeasurementError:
                continue
            shift = abs(math.remainder(solved.pose_change[2] - exact.pose_change[2], math.tau))
            sigmas = shift / math.sqrt(solved.cov[2, 2])
            if best is None or sigmas > best[0]:
                best = (sigmas, index, typed[index])
    assert best is not None, "every 10 mm typo is inconsistent here"
    assert best[0] > 4.0, f"no 10 mm typo puts the heading over 4 sd off ({best[0]:.1f})"
    return best[1], best[2]


def test_a_typo_is_caught_and_only_that_distance_is_re_entered(tmp_path: Path) -> None:
    """Measured: d3 typed 0.0278 instead of 0.0178 was accepted as clean with
    the heading 8 sigma off. Now the slip check asks to re-measure the typed
    distance by name, and re-entering it alone completes the trial."""
    robot = tmp_path / "robot.toml"
    robot.write_text(ROBOT_TOML)
    folder = tmp_path / "session"
    args = ["--seed", "5", "--time-scale", FAST, "--no-pacing"]
    with EmulatorProcess(args, use_cli=True) as emu, TruthClient(emu.truth_socket) as truth:
        child = _spawn(["--port", emu.device, "--robot", str(robot), "--plan", "k=1,l=3,n=4",
                        "--session", str(folder)])  # fmt: skip
        typed_first: list[float] = []
        for trial in (1, 2, 3):
            values = _marks(child, truth)
            child.expect(_prompt(0))
            # trial 1 typed with more digits than a float holds ("0.1 + tiny digits")
            _type_all(child, values, f"Trial {trial} solved", "00000000007" if trial == 1 else "")
            typed_first = typed_first or [float(repr(v) + "00000000007") for v in values]
        values = _marks(child, truth)
        child.expect(_prompt(0))
        index, typed = _absorbed_typo(values)
        wrong = list(values)
        wrong[index] = typed
        _type_all(child, wrong, re.escape(f"Re-measure {LABELS[index]}, metres"))
        child.sendline(repr(values[index]))
        child.expect("Trial 4 solved")
        child.expect(r"Session complete:\S* 4 trials")
        child.expect(pexpect.EOF)
        child.close()
    records = read_journal(folder).records
    remeasured = [r.data for r in records if r.kind == Remeasured.KIND]
    assert [(d["trial"], d["index"], d["kept"]) for d in remeasured] == [(4, index, False)]
    assert sum(1 for r in records if r.kind == Measurement.KIND and r.data["trial"] == 4) == len(
        values
    )
    state = replay(records)
    assert state.completed[-1].readings.values == pytest.approx(values)  # type: ignore[union-attr]
    assert not state.completed[-1].flag_reason
    # a typed distance stays the one float Python parses from the text, up to the journal
    journaled = [r.data["value_m"] for r in records if r.kind == Measurement.KIND]
    assert journaled[: len(typed_first)] == typed_first
    assert all(type(v) is float for v in journaled)


def test_a_plan_that_cannot_be_estimated_is_refused_before_anything_moves(
    tmp_path: Path,
) -> None:
    """Before: a one-trial plan was driven and the session ended with no
    estimate. Now pre-flight refuses it (its own check, as ``run`` does): exit
    2, not a command reaches the robot, no session folder."""
    robot = tmp_path / "robot.toml"
    robot.write_text(ROBOT_TOML)
    folder = tmp_path / "session"
    args = ["--seed", "3", "--time-scale", "8", "--no-pacing"]
    with EmulatorProcess(args, use_cli=True) as emu, TruthClient(emu.truth_socket) as truth:
        before = _pose(truth)
        child = _spawn(["--port", emu.device, "--robot", str(robot), "--plan", "k=0.5,l=2,n=1",
                        "--session", str(folder)])  # fmt: skip
        child.expect(r"\[FAIL\]\s+(\x1b\[[0-9;]*m)*plan estimable")
        child.expect("no estimate could come of these trials")
        child.expect("n=2 or more")  # what would make it estimable
        child.expect("Pre-flight failed: nothing was moved")
        child.expect(pexpect.EOF)
        child.close()
        assert child.exitstatus == 2
        time.sleep(0.3)
        snap = truth.snapshot()
        assert snap.motion_log == ()
        assert not snap.moving
        assert _pose(truth) == before
    assert not folder.exists()


def test_resume_after_ctrl_c_mid_motion_asks_to_put_the_robot_back(tmp_path: Path) -> None:
    robot = tmp_path / "robot.toml"
    robot.write_text(ROBOT_TOML)
    folder = tmp_path / "session"
    args = ["--seed", "3", "--time-scale", "8", "--no-pacing"]
    with EmulatorProcess(args, use_cli=True) as emu, TruthClient(emu.truth_socket) as truth:
        child = _spawn(["--port", emu.device, "--robot", str(robot), "--plan", "k=0.5,l=2,n=2",
                        "--session", str(folder)])  # fmt: skip
        child.expect("Mark the floor at the 3 screws")
        start = _pose(truth)
        child.sendline("")
        child.expect("driving k=0.5")
        deadline = time.monotonic() + TIMEOUT_S
        while math.hypot(_pose(truth)[0] - start[0], _pose(truth)[1] - start[1]) < 0.3:
            assert time.monotonic() < deadline
            time.sleep(0.01)
        child.sendintr()
        child.expect(r"Interrupted\S* \(Ctrl-C\)")
        child.expect(pexpect.EOF)
        child.close()
        assert child.exitstatus == 130

        # before: the wizard started trial 1 again from where the robot stood
        child = _spawn(["--port", emu.device, "--session", str(folder)])
        child.expect(r"heading=[-+]\d")
        child.expect("the robot is [0-9.]+ m away")
        child.expect("Put the robot back where trial 1 starts")
        child.sendline("")
        child.expect("Encoders set to the trial's start")
        values = _marks(child, truth)
        child.expect(_prompt(0))
        _type_all(child, values, "Trial 1 solved")
        values = _marks(child, truth)  # trial 2 (a one-trial plan is refused before motion)
        child.expect(_prompt(0))
        _type_all(child, values, "Trial 2 solved")
        child.expect(r"Session complete:\S* 2 trials\.")
        child.expect("verdict: DOUBTFUL")
        child.expect("fewer than 10 trials a design")
        child.expect(pexpect.EOF)
        child.close()
        # the two trials of the emulator at seed 3, typed exactly: doubtful for being
        # below the planner's minimum trials a design
        assert child.exitstatus == 3, child.before
    kinds = [r.kind for r in read_journal(folder).records]
    assert kinds.count(ev.START_POSE) == 2


def test_resumed_mid_trial_shows_its_context_and_back_corrects_the_last_value(
    tmp_path: Path,
) -> None:
    """Before: a resumed wizard landed on a bare "d2 (screw B)" prompt, and a
    value typed could not be corrected. Now the resumed trial is shown (number,
    design, what was entered), and ``back`` at the next prompt corrects the
    value typed just before it: the wrong one never reaches the journal."""
    robot = tmp_path / "robot.toml"
    # the fake is the paper's Nomad: said so, its priors tell trial 2's pose
    # from the runner-up that two crosses leave (without, it asks a third)
    robot.write_text(ROBOT_TOML + "[priors]\n")
    folder = tmp_path / "session"
    args = ["--seed", "4", "--time-scale", FAST, "--no-pacing"]
    with EmulatorProcess(args, use_cli=True) as emu, TruthClient(emu.truth_socket) as truth:
        child = _spawn(["--port", emu.device, "--robot", str(robot), "--plan", "k=1,l=1,n=2",
                        "--session", str(folder)])  # fmt: skip
        values = _marks(child, truth)
        child.expect(re.escape(f"Trial 1/2, {LABELS[0]}, metres ("))
        _answer(child, repr(values[0]), _prompt(1))
        _answer(child, repr(values[1]), _prompt(2))  # d1 is saved once d2 is typed
        child.sendintr()
        child.expect(r"Interrupted\S* \(Ctrl-C\)")
        child.expect(pexpect.EOF)
        child.close()
        assert child.exitstatus == 130

        child = _spawn(["--port", emu.device, "--session", str(folder)])
        child.expect(r"Trial 1/2\S* \(attempt 1\): k=1 l=1 m")
        child.expect("resumed: the motion is done")
        child.expect(re.escape(f"Already entered and saved: {LABELS[0]} = {values[0]:.4f} m"))
        child.expect(re.escape(f"Trial 1/2, {LABELS[1]}, metres ("))
        child.sendline("back")  # nothing typed in this run yet: nothing to correct
        child.expect("nothing to go back to")
        child.expect(_prompt(1))
        _answer(child, repr(values[1] + 0.002), re.escape(f"back: correct {LABELS[1]}"))
        child.sendline("-")
        child.expect(re.escape(f"Correct {LABELS[1]}"))
        _answer(child, repr(values[1]), _prompt(2))
        _type_all_from(child, values, 2, "Trial 1 solved")
        second = _marks(child, truth)  # trial 2 (a one-trial plan is refused before motion)
        child.expect(_prompt(0))
        _type_all(child, second, "Trial 2 solved")
        child.expect(r"Session complete:\S* 2 trials\.")
        child.expect(pexpect.EOF)
        child.close()
    records = read_journal(folder).records
    typed = [r.data["value_m"] for r in records if r.kind == Measurement.KIND]
    assert typed == values + second
    assert "KeyboardInterrupt" not in journal_path(folder).read_text()


def test_the_wizard_connects_with_robot_toml_serial_and_says_so(tmp_path: Path) -> None:
    """No --port, no --baud: robot.toml's [serial] gives both, the banner says so."""
    args = ["--time-scale", "20000", "--seed", "3", "--baud", "9600"]
    with EmulatorProcess([*args, "--truth-socket", str(tmp_path / "t.sock")]) as emulator:
        robot = tmp_path / "robot.toml"
        serial = f'[serial]\nport = "{emulator.device}"\nbaud = 9600\n'
        robot.write_text(ROBOT_TOML + serial, encoding="utf-8")
        child = _console(
            ["--robot", str(robot), "--plan", "k=1,l=1,n=2", "--session", str(tmp_path / "s")]
        )
        child.expect("press Enter to start the motion")
        shown = re.sub(r"\x1b\[[0-9;]*m", "", child.before)  # bold names
        shown = re.sub(r"\s*\r?\n\s*", " ", shown)  # the terminal wraps long lines
        where = f"({robot} [serial])"
        banner = f"robot answers: nomad150 on {emulator.device} {where} at 9600 baud {where}"
        assert banner in shown, shown
        child.sendintr()
        child.expect(pexpect.EOF)
        child.close()
    assert child.exitstatus == 130
    header = read_journal(tmp_path / "s").records[0].data
    assert (header["settings"]["port"], header["settings"]["baud"]) == (emulator.device, 9600)


def test_the_wizard_drives_a_plan_of_squares(tmp_path: Path) -> None:
    """Issue 19: a plan may name general paths; the operator marks the floor
    as for a forth-and-back trial, the wizard drives the square and takes the
    tape's distances; the session estimates with the general-path recipe."""
    robot = tmp_path / "robot.toml"
    robot.write_text(ROBOT_TOML)
    folder = tmp_path / "session"
    args = ["--seed", "6", "--time-scale", FAST, "--no-pacing"]
    with EmulatorProcess(args, use_cli=True) as emu, TruthClient(emu.truth_socket) as truth:
        child = _spawn(["--port", emu.device, "--robot", str(robot), "--plan",
                        "path=square:0.5,cw,n=5", "--session", str(folder)])  # fmt: skip
        for trial in range(1, 6):  # the fewest trials of squares that estimate the four
            child.expect(re.escape(f"Trial {trial}/5") + r".*square 0\.5 m cw, 2 m of driving")
            values = _marks(child, truth)
            child.expect(_prompt(0))
            # a square ends near its start: the marks may ask for one more cross
            # distance to tell the motion from its inverse; skipping leaves it out
            _type_all(child, values, f"(Trial {trial} (solved|left out)|ne more distance)")
            if "ne more distance" in str(child.after):
                child.sendline("")
                child.expect(f"Trial {trial} (solved|left out)")
        child.expect(r"Session complete:\S* 5 trials")
        child.expect(pexpect.EOF)
        child.close()
    state = replay(read_journal(folder).records)
    assert [t.design.label() for t in state.completed] == ["square 0.5 m cw"] * 5
    assert state.plan is not None
    assert state.plan.to_text() == "path=square:0.5,cw,n=5"
