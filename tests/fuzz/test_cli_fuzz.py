"""Property-based fuzz of every command's numeric options, trial files,
robot descriptions and CRC-valid journal headers (issue 9, acceptance).

Each case runs the CLI in-process through typer's runner (the same ``app``
as the console script) under a per-case time bound: no traceback, no hang,
exit 2 with a message naming the problem, or a normal exit for a valid case.
More than 2000 cases in all; a couple of minutes on a loaded 2-core machine.
"""

from __future__ import annotations

import functools
import itertools
import math
import signal
from collections.abc import Iterator
from pathlib import Path
from types import FrameType
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner, Result

from odohil.cli.app import app
from odohil.science.limits import RANGES
from odohil.session.journal import events as ev
from odohil.session.journal.file import Journal

CASE_SECONDS = 20.0
"""Per-case time bound: a case that takes longer is a hang."""
NO_PORT = "/dev/odohil-fuzz-no-such-port"
ROBOT_TOML = """\
[screws]
A = [0.20, 0.0]
B = [-0.10, 0.173]
C = [-0.10, -0.173]
[measurement]
sigma_m = 0.001
cross = [["A", "B"]]
"""


class CaseTimeout(Exception):
    """A fuzz case ran past its time bound."""


def _alarm(signum: int, frame: FrameType | None) -> None:
    raise CaseTimeout(f"a case took more than {CASE_SECONDS} s")


@pytest.fixture(autouse=True)
def _alarm_handler() -> Iterator[None]:
    previous = signal.signal(signal.SIGALRM, _alarm)
    yield
    signal.setitimer(signal.ITIMER_REAL, 0.0)
    signal.signal(signal.SIGALRM, previous)


def invoke(args: list[str]) -> Result:
    signal.setitimer(signal.ITIMER_REAL, CASE_SECONDS)
    try:
        return CliRunner().invoke(app, args)
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0.0)


def flat(result: Result) -> str:
    text = result.output
    for mark in "│╭╮╰╯─\n":
        text = text.replace(mark, " ")
    return " ".join(text.split())


def check(result: Result, allowed: set[int], names: list[str]) -> None:
    """No traceback, no hang; an allowed exit; exit 2 names one of ``names``."""
    exc = result.exception
    assert exc is None or isinstance(exc, SystemExit), f"{exc!r}\n{result.output}"
    assert result.exit_code in allowed, result.output
    if result.exit_code == 2:
        text = flat(result)
        assert any(name in text for name in names), text


SETTINGS = settings(
    deadline=None,
    database=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
)

HOSTILE = st.sampled_from(
    ["nan", "inf", "-inf", "1e300", "-1e300", "1e9", "-5", "0", "-0", "1e-300", "abc", "",
     "0x10", "1_000", " 3", "1e400", "12345678901234567890"]
)  # fmt: skip
NUMBER_TEXT = st.one_of(
    HOSTILE,
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
    st.integers(-(10**20), 10**20).map(str),
    st.floats(-200.0, 200.0).map(lambda v: f"{v:g}"),
)


def in_range(name: str, text: str) -> bool:
    """Whether ``text`` is a valid value of option ``name``."""
    bound = RANGES[name]
    try:
        value = int(text) if bound.integer else float(text)
    except ValueError:
        return False
    ok = math.isfinite(value) and bound.low <= value <= bound.high
    return ok and (not bound.half or float(2 * value).is_integer())


def options(names: dict[str, str], draw: Any) -> tuple[list[str], bool]:
    """Some of ``names`` (option -> range name) with fuzzed values, and
    whether every value given is valid."""
    args: list[str] = []
    valid = True
    for option, name in names.items():
        if draw(st.booleans()):
            text = draw(NUMBER_TEXT)
            args += [option, text]
            valid = valid and in_range(name, text)
    return args, valid


PARAMETERS = {"--E-R": "E_R", "--E-T": "E_T", "--K-theta": "K_theta", "--K-rho": "K_rho"}
NAMES = ["--", "must be", "Invalid value", "not a valid", "Missing option"]


@pytest.mark.slow
@settings(SETTINGS, max_examples=400)
@given(data=st.data())
def test_predict_and_covariance(data: st.DataObject) -> None:
    command = data.draw(st.sampled_from(["predict", "covariance-fb", "covariance-square"]))
    extra, _ = options(PARAMETERS, data.draw)
    if command == "covariance-square":
        side = data.draw(NUMBER_TEXT)
        args = ["covariance", "--path", "square", "--side", side]
    else:
        k, l_m = data.draw(NUMBER_TEXT), data.draw(NUMBER_TEXT)
        head = ["predict"] if command == "predict" else ["covariance", "--path", "forth-and-back"]
        args = [*head, "--k", k, "--l", l_m]
    check(invoke(args + extra + ["--json"]), {0, 2}, NAMES)


@pytest.mark.slow
@settings(SETTINGS, max_examples=200)
@given(data=st.data())
def test_simulate_and_covariance_simulation(data: st.DataObject, tmp_path: Path) -> None:
    trials = data.draw(st.one_of(HOSTILE, st.integers(1, 40).map(str)))
    segment = data.draw(st.one_of(HOSTILE, st.sampled_from(["0.05", "0.1", "1"])))
    seed = data.draw(st.one_of(HOSTILE, st.integers(0, 2**64).map(str)))
    k, l_m = data.draw(NUMBER_TEXT), data.draw(NUMBER_TEXT)
    extra, _ = options(PARAMETERS, data.draw)
    if data.draw(st.booleans()):
        args = ["simulate", "--k", k, "--l", l_m, "--trials", trials,
                "--out", str(tmp_path / "sim.csv")]  # fmt: skip
    else:
        args = ["covariance", "--path", "forth-and-back", "--k", k, "--l", l_m,
                "--simulate", trials]  # fmt: skip
    args += ["--segment-m", segment, "--seed", seed, *extra]
    check(invoke(args), {0, 2}, NAMES)


PLAN_OPTIONS = {
    "--budget-m": "budget_m", "--max-trials": "max_trials", "--sigma-m": "sigma_m",
    "--target-E-R": "target_E_R", "--target-E-T": "target_E_T",
    "--target-K-theta": "target_K_theta", "--target-K-rho": "target_K_rho",
    "--max-designs": "max_designs", "--max-leg-m": "max_leg_m",
    "--min-trials-per-design": "min_trials_per_design", "--measure-s": "measure_s",
    "--budget-min": "budget_min", "--speed": "speed", **PARAMETERS,
}  # fmt: skip


@pytest.mark.slow
@settings(SETTINGS, max_examples=200)
@given(data=st.data())
def test_plan_refuses_every_bad_number(data: st.DataObject) -> None:
    args, _ = options(PLAN_OPTIONS, data.draw)
    # one option surely out of range, so that no case spends seconds planning
    option = data.draw(st.sampled_from(sorted(PLAN_OPTIONS)))
    bad = data.draw(NUMBER_TEXT.filter(lambda t: not in_range(PLAN_OPTIONS[option], t)))
    args = ["plan", "--budget-m", "100", *args, option, bad]
    check(invoke(args), {2}, NAMES)


EXPORT_OPTIONS = {
    "--speed": "speed", "--rate-hz": "rate_hz", "--update-min-d-m": "update_min_d_m",
    "--update-min-a-rad": "update_min_a_rad",
}  # fmt: skip


@settings(SETTINGS, max_examples=60)
@given(data=st.data())
def test_export_refuses_every_bad_number(data: st.DataObject, tmp_path: Path) -> None:
    args, _ = options(EXPORT_OPTIONS, data.draw)
    option = data.draw(st.sampled_from(sorted(EXPORT_OPTIONS)))
    bad = data.draw(NUMBER_TEXT.filter(lambda t: not in_range(EXPORT_OPTIONS[option], t)))
    args = ["export", str(tmp_path), "--format", "amcl", *args, option, bad]
    check(invoke(args), {2}, NAMES)


SESSION_OPTIONS = {"--seed": "seed", "--baud": "baud"}


@pytest.mark.slow
@settings(SETTINGS, max_examples=250)
@given(data=st.data())
def test_session_commands_refuse_bad_numbers_before_the_port(
    data: st.DataObject, tmp_path: Path
) -> None:
    robot = tmp_path / "robot.toml"
    robot.write_text(ROBOT_TOML)
    command = data.draw(st.sampled_from(["run", "resume", "wizard", "demo", "emulate"]))
    extra, _ = options(SESSION_OPTIONS, data.draw)
    if command == "emulate":
        names = {**SESSION_OPTIONS, "--time-scale": "time_scale", **PARAMETERS}
        extra, _ = options(names, data.draw)
        option = data.draw(st.sampled_from(sorted(names)))
        bad = data.draw(NUMBER_TEXT.filter(lambda t: not in_range(names[option], t)))
        check(invoke(["emulate", *extra, option, bad]), {2}, NAMES)
        return
    if command in ("wizard", "demo"):  # a valid one would start a session: break one
        bad = data.draw(NUMBER_TEXT.filter(lambda t: not in_range("seed", t)))
        option = "--seed" if command == "demo" else "--baud"
        if command == "wizard":
            bad = data.draw(NUMBER_TEXT.filter(lambda t: not in_range("baud", t)))
        check(invoke([command, "--port", NO_PORT, option, bad]), {2}, NAMES)
        return
    if command == "resume":
        extra = _without(extra, "--seed")
        args = ["resume", str(tmp_path / "no-session"), *extra]
        check(invoke(args), {2}, [*NAMES, "journal"])
        return
    plan = data.draw(st.one_of(st.just("k=1,l=1,n=3"), _plans()))
    args = ["run", "--allow-few-trials", "--port", NO_PORT, "--robot", str(robot), "--plan", plan,
            "--measure", "fake", "--session", str(tmp_path / "s"), *extra]  # fmt: skip
    result = invoke(args)
    check(result, {1, 2}, NAMES)
    if result.exit_code == 1:
        assert NO_PORT in flat(result)  # it got past every check, to the port
    assert not (tmp_path / "s").exists() or result.exit_code == 1


def _without(args: list[str], option: str) -> list[str]:
    out: list[str] = []
    skip = False
    for arg in args:
        if skip:
            skip = False
            continue
        if arg == option:
            skip = True
            continue
        out.append(arg)
    return out


@st.composite
def _plans(draw: Any) -> str:
    designs = []
    for _ in range(draw(st.integers(1, 3))):
        k, l_m = draw(NUMBER_TEXT), draw(NUMBER_TEXT)
        n = draw(st.one_of(HOSTILE, st.integers(-3, 10**9).map(str)))
        designs.append(f"k={k},l={l_m},n={n}")
    return ";".join(designs)


K_TEXT = st.one_of(HOSTILE, st.sampled_from(["0.5", "1", "2", "20", "1.5"]))
L_TEXT = st.one_of(HOSTILE, st.sampled_from(["0.5", "1", "6", "2"]))
VALUE_TEXT = st.one_of(HOSTILE, st.floats(-1.0, 1.0).map(repr))


@pytest.mark.slow
@settings(SETTINGS, max_examples=350)
@given(data=st.data())
def test_trial_files(data: st.DataObject, tmp_path: Path) -> None:
    header = "k,l_m,variant,dx_m,dy_m,dtheta_rad"
    if data.draw(st.booleans()):
        header = "\ufeff" + header
    rows = []
    for _ in range(data.draw(st.integers(0, 8))):
        fields = [data.draw(K_TEXT), data.draw(L_TEXT),
                  data.draw(st.sampled_from(["turn", "reverse", "sideways", ""]))]  # fmt: skip
        fields += [data.draw(VALUE_TEXT) for _ in range(3)]
        if data.draw(st.integers(0, 20)) == 0:
            fields[3] = "9" * data.draw(st.sampled_from([5000, 140_000]))
        rows.append(",".join(fields))
    path = tmp_path / "trials.csv"
    path.write_text("\n".join([header, *rows]) + "\n", encoding="utf-8")
    result = invoke(["estimate", str(path), "--json"])
    check(result, {0, 2, 3}, ["line", "trials", "column", "no trials", "not enough", "error"])
    assert "unknown column" not in flat(result)


TOML_VALUE = st.one_of(
    st.floats(allow_nan=False, allow_infinity=False).map(repr),
    st.sampled_from(["nan", "inf", "-inf", "1e-300", "1e300", "0.0", "-0.001", '"abc"', "[1, 2]",
                     "true", "0.001", "0.0005", "{}"]),
    st.integers(-(10**12), 10**12).map(str),
)  # fmt: skip


@pytest.mark.slow
@settings(SETTINGS, max_examples=250)
@given(data=st.data())
def test_robot_descriptions(data: st.DataObject, tmp_path: Path) -> None:
    value = lambda: data.draw(TOML_VALUE)  # noqa: E731
    text = (
        "[screws]\n"
        f"A = [{value()}, 0.0]\nB = [-0.10, {value()}]\nC = [-0.10, -0.173]\n"
        f'[measurement]\nsigma_m = {value()}\ncross = [["A", "B"]]\n'
    )
    if data.draw(st.booleans()):
        text += f'[serial]\nport = "/dev/x"\nbaud = {value()}\ntimeout_s = {value()}\n'
    robot = tmp_path / "robot.toml"
    robot.write_text(text)
    trials = tmp_path / "t.csv"
    trials.write_text("k,l_m,variant,d1_m,d2_m,d3_m,cross1_m\n1,1,turn,0.01,0.01,0.01,0.35\n")
    result = invoke(["estimate", str(trials), "--robot", str(robot)])
    check(result, {0, 2, 3}, ["robot.toml", "screws", "sigma_m", "serial", "TOML", "line"])


@functools.cache
def _jsonish() -> st.SearchStrategy[Any]:
    """Any JSON-like value. One strategy object for the whole module: hypothesis
    validates a new recursive strategy on its first draw, and _headers drew
    from a new one eleven times per example (about 40 ms each: most of the
    test's time, none of it the command under test)."""
    leaves = st.one_of(
        st.none(), st.booleans(), st.integers(-(10**20), 10**20), st.text(max_size=8),
        st.floats(allow_nan=False, allow_infinity=False),
    )  # fmt: skip
    return st.recursive(
        leaves,
        lambda inner: st.one_of(
            st.lists(inner, max_size=3), st.dictionaries(st.text(max_size=6), inner, max_size=3)
        ),
        max_leaves=8,
    )


@st.composite
def _headers(draw: Any) -> dict[str, Any]:
    design = {
        "k": draw(st.one_of(st.sampled_from([1, 0.5, 1e9, -1, "abc", None]), _jsonish())),
        "l_m": draw(st.one_of(st.sampled_from([1.0, 100.0, 0.001, 1e300, "x"]), _jsonish())),
        "variant": draw(st.sampled_from(["turn", "reverse", "spin", 3])),
        "n": draw(st.one_of(st.sampled_from([3, 0, -1, 10**12, 2.5, "3"]), _jsonish())),
    }
    header: dict[str, Any] = {
        "format": ev.FORMAT,
        "robot_toml": draw(st.one_of(st.just(ROBOT_TOML), _jsonish(), st.text(max_size=20))),
        "measure": draw(st.one_of(st.sampled_from(["fake", "file", "operator"]), _jsonish())),
        "settings": draw(
            st.one_of(
                st.fixed_dictionaries(
                    {
                        "port": st.one_of(st.just(NO_PORT), _jsonish()),
                        "seed": st.one_of(st.integers(-5, 2**70), _jsonish()),
                        "baud": st.one_of(st.sampled_from([9600, 0, -1, 10**12]), _jsonish()),
                    }
                ),
                _jsonish(),
            )
        ),
        "plan": draw(st.one_of(st.just({"designs": [design]}), _jsonish())),
    }
    for member in ("robot_toml", "measure", "settings", "plan"):
        if draw(st.integers(0, 6)) == 0:
            del header[member]
    return header


_FOLDERS = itertools.count()


@pytest.mark.slow
@settings(SETTINGS, max_examples=350)
@given(header=_headers(), command=st.sampled_from(["resume", "estimate", "report"]))
def test_crc_valid_journal_headers(header: dict[str, Any], command: str, tmp_path: Path) -> None:
    folder = tmp_path / f"s{next(_FOLDERS)}"
    with Journal.create(folder) as journal:  # the journal's own writer: CRCs are valid
        journal.append(ev.SESSION, header)
    args = [command, str(folder)]
    if command == "report":
        args += ["--out", str(folder / "report")]
    result = invoke(args)
    allowed = {0, 1, 2, 3} if command == "resume" else {0, 2, 3}
    check(result, allowed, ["record", "session", "plan", "journal", "robot", "trials"])
    if command == "resume" and result.exit_code == 1:
        assert "port" in flat(result)  # only once every check passed
