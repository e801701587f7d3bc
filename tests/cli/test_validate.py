"""``odohil validate`` through the CLI, as a user runs it.

Acceptance (issue 11, item 2): a session calibrated with ``odohil run`` on
the fake robot passes validation on a path it was not fitted on, driven on a
fake with the same parameters, and fails on a fake whose E_R is three times
and K_theta nine times larger; over three seeds. Bad input exits 2 before
anything moves; a trial file and a square's pose file are read without a robot.

Trial counts (docs/validation.md): the calibration drives
``k=1,l=3,n=12;k=10,l=0.5,n=12`` (24 trials, 120 m); each validation drives
VALIDATION_TRIALS trials of ``forth-back:2,1.5`` (6 m each). Against the
mis-calibrated fake the heading residual alone is about 2.4 deg per trial
for a predicted spread near 0.3 deg, so the theta test's NEES is about 40
per trial against a threshold of 18 for all six: the power is 1 to many
digits. Under the calibrated model each seed fails with probability at most
alpha = 1 %.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from typer.testing import CliRunner

from odohil.cli.app import app
from odohil.science.parameters import NOMAD150
from odohil.science.paths import Design
from odohil.science.simulator import simulate
from tests.once import made_once
from tests.session.test_trust_runs import readme_robot

CALIBRATION_PLAN = "k=1,l=3,n=12;k=10,l=0.5,n=12"
VALIDATION_PATH = "forth-back:2,1.5"
VALIDATION_TRIALS = 6
SEEDS = (1, 2, 3)
WRONG = f"E_R={3 * -0.202:g}&K_theta={9 * 0.012:g}"
"""The mis-calibrated fake: E_R 3x and K_theta 9x the Nomad 150's (paper units)."""


class Done:
    """What a command left: exit status, stdout, stderr."""

    def __init__(self, returncode: int, stdout: str, stderr: str) -> None:
        self.returncode, self.stdout, self.stderr = returncode, stdout, stderr


def in_process(*args: str) -> Done:
    """``odohil ARGS`` in this process (typer's CliRunner on odohil.cli.app's app:
    the same parsing, session and rendering as the console script, without a
    process start; the fake robot of ``fakerobot://`` runs in process either way)."""
    result = CliRunner().invoke(app, list(args))
    assert result.exception is None or isinstance(result.exception, SystemExit), repr(
        result.exception
    )
    return Done(result.exit_code, result.stdout, result.stderr)


odohil = in_process
"""Every command of these tests runs in process (they were processes before)."""


def calibrate(folder: Path, seed: int) -> Path:
    robot = folder / "robot.toml"
    robot.write_text(readme_robot(), encoding="utf-8")
    session = folder / "calibration"
    port = f"fakerobot://?seed={seed}&time_scale=2000"
    done = odohil(
        "run", "--allow-few-trials",
        "--port", port, "--robot", str(robot), "--plan", CALIBRATION_PLAN,
        "--measure", "fake", "--seed", str(seed), "--session", str(session), "--json",
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    return session


def calibrated(factory: pytest.TempPathFactory, seed: int, folder: Path) -> Path:
    """:func:`calibrate` of ``seed`` copied into ``folder``, calibrated once a test run.

    The module's quick tests and the seed-1 cell both want seed 1's calibration,
    and each xdist worker would otherwise run it again (the same seeded run: the
    same journal): tests/once.py.
    """
    made_once(
        factory, f"validate-calibration-{seed}", lambda shared: calibrate(shared, seed), folder
    )
    return folder / "calibration"


def validate(session: Path, port_query: str, seed: int, out: Path) -> tuple[int, dict[str, Any]]:
    default = out.name == "forth-back-k2-l1.5-turn"
    done = odohil(
        "validate", str(session), "--path", VALIDATION_PATH, "--trials", str(VALIDATION_TRIALS),
        "--port", f"fakerobot://?{port_query}", "--measure", "fake", "--seed", str(seed),
        *([] if default else ["--out", str(out)]), "--json",
    )  # fmt: skip
    assert done.stdout.strip(), (done.returncode, done.stderr)  # the callers assert 0 or 3
    return done.returncode, json.loads(done.stdout)


@pytest.mark.slow
@pytest.mark.parametrize("seed", SEEDS)
def test_passes_on_the_calibrated_fake_and_fails_on_a_wrong_one(
    tmp_path_factory: pytest.TempPathFactory, tmp_path: Path, seed: int
) -> None:
    session = calibrated(tmp_path_factory, seed, tmp_path)
    other = seed + 100  # the validation drives other draws than the calibration
    good_folder = session / "validation" / "forth-back-k2-l1.5-turn"  # the default
    bad_folder = session / "validation" / "wrong-robot"
    code, good = validate(session, f"seed={other}&time_scale=2000", other, good_folder)
    assert (code, good["verdict"]["status"]) == (0, "pass"), good["verdict"]
    assert good["n_trials"] == VALIDATION_TRIALS
    assert good["verdict"]["overall"]["dof"] == 3 * VALIDATION_TRIALS
    assert good["verdict"]["parameter_uncertainty"].startswith("included")
    # what the pass rules out: the mean parameters, SI, caught by a bias test
    detectable = good["verdict"]["detectable"]
    assert list(detectable) == ["E_R", "E_T"]
    for name in detectable:
        assert 0 < detectable[name]["error"] < 1, detectable
        assert detectable[name]["test"].startswith("bias")
        assert detectable[name]["power"] == 0.9
    code, bad = validate(session, f"seed={other}&time_scale=2000&{WRONG}", other, bad_folder)
    assert (code, bad["verdict"]["status"]) == (3, "fail"), bad["verdict"]
    assert "theta" in bad["verdict"]["failed"]
    for name, result in (("same", good), ("wrong", bad)):
        v = result["verdict"]
        figures = ", ".join(
            f"{t} {v['axes'][t]['nees']:.3g} (p {v['axes'][t]['p_value']:.2g})" for t in v["axes"]
        )
        print(  # noqa: T201  (the acceptance figures, shown with pytest -s)
            f"seed {seed} {name} fake: {v['status']} NEES {v['overall']['nees']:.4g}/"
            f"{v['overall']['dof']} dof, p {v['overall']['p_value']:.3g}, "
            f"threshold {v['overall']['threshold']:.4g}; {figures}"
        )
    # the validation trials are journaled in their own sessions, not the calibration's
    calibration_log = (session / "journal.jsonl").read_text(encoding="utf-8")
    assert calibration_log.count('"kind":"solved"') == 24
    assert good["validation_session"] == str(good_folder)
    # the report shows both validations against their predicted ellipses
    report = in_process("report", str(session), "--out", str(tmp_path / "report"), "--force")
    assert report.returncode == 0, report.stderr
    page = (tmp_path / "report" / "index.html").read_text(encoding="utf-8")
    section = page[page.index('id="validation"') :]
    assert section.count('<figure id="validation-') == 2
    assert "PASS" in section
    assert "FAIL" in section
    assert section.count("what a pass rules out: with probability 90 %") == 2
    # a finished validation is tested again without a robot
    again = odohil(
        "validate", str(session), "--path", VALIDATION_PATH, "--json",
    )  # fmt: skip
    assert again.returncode == 0, again.stderr
    assert json.loads(again.stdout)["verdict"] == good["verdict"]


@pytest.fixture(scope="module")
def session(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """One calibrated session shared by the quick tests."""
    return calibrated(tmp_path_factory, 1, tmp_path_factory.mktemp("validate"))


@pytest.mark.parametrize(
    ("args", "names"),
    [
        (["--path", "circle:2"], ["--path", "square:SIDE"]),
        (["--path", "square:0"], ["SIDE", "0.001"]),
        (["--path", "forth-back:0.3,1"], ["--path", "multiple of 1/2"]),
        (["--path", "forth-back:1,3", "--trials", "3", "--measure", "fake"], ["calibration"]),
        (["--path", "forth-back:2,1.5", "--measure", "fake"], ["--trials"]),
        (["--path", "square:1", "--measure", "fake"], ["--trials"]),
        (["--path", "square:1,up", "--trials", "3", "--measure", "fake"], ["--path", "cw"]),
        (["--path", "forth-back:2,1.5", "--trials", "0"], ["--trials", "10000"]),
        (["--path", "forth-back:2,1.5", "--alpha", "0.7"], ["--alpha", "0.5"]),
    ],
)
def test_bad_input_exits_2_naming_the_option(
    session: Path, args: list[str], names: list[str]
) -> None:
    done = in_process("validate", str(session), *args)
    assert done.returncode == 2, (done.stdout, done.stderr)
    message = " ".join(done.stderr.split())
    for name in names:
        assert name in message, message
    assert not (session / "validation").exists()  # nothing driven, nothing journaled


def _pose_rows(design: Design | None, poses: np.ndarray) -> str:
    if design is None:
        rows = ["dx_m,dy_m,dtheta_rad,sigma_x_m,sigma_y_m,sigma_theta_rad"]
        rows += [f"{x!r},{y!r},{t!r},0.001,0.001,0.002" for x, y, t in poses.tolist()]
    else:
        rows = ["k,l_m,variant,dx_m,dy_m,dtheta_rad"]
        rows += [
            f"{design.k:g},{design.l_m!r},turn,{x!r},{y!r},{t!r}" for x, y, t in poses.tolist()
        ]
    return "\n".join(rows) + "\n"


def test_trial_file_and_square_pose_file_are_read_without_a_robot(
    session: Path, tmp_path: Path
) -> None:
    """Simulated trials at the Nomad values pass; the same with E_R tripled fail."""
    design = Design(2, 1.2)
    wrong = NOMAD150.__class__(3 * NOMAD150.e_r, NOMAD150.e_t, 9 * NOMAD150.k_theta, 1e-5)
    for params, expected in ((NOMAD150, 0), (wrong, 3)):
        poses = simulate(design.path(), params, 8, seed=4, segment_m=0.005).pose_change
        poses = poses + np.random.default_rng(1).normal(0, [1e-3, 1e-3, 2e-3], poses.shape)
        file = tmp_path / f"trials-{expected}.csv"
        file.write_text(_pose_rows(design, poses), encoding="utf-8")
        done = in_process("validate", str(session), "--path", f"file:{file}", "--json")
        assert done.returncode == expected, done.stderr
        assert json.loads(done.stdout)["n_trials"] == 8
    from odohil.science.paths import square

    poses = simulate(square(1.5), wrong, 8, seed=5, segment_m=0.005).pose_change
    file = tmp_path / "square.csv"
    file.write_text(_pose_rows(None, poses), encoding="utf-8")
    done = in_process("validate", str(session), "--path", "square:1.5", "--measure", str(file))
    assert done.returncode == 3, done.stderr
    assert "FAIL" in done.stdout
    done = in_process("validate", str(session), "--path", "square:1.5", "--measure", str(file),
                  "--trials", "9")  # fmt: skip
    assert done.returncode == 2
    assert "--trials 9" in done.stderr


def test_motion_capture_is_checked_before_anything_moves(session: Path, tmp_path: Path) -> None:
    """`--measure tcp://HOST:PORT` goes to the motion-capture source, checked
    before any validation session or port: here the calibration's robot
    description has no [measurement] pose_sigma, so it is bad input."""
    out = tmp_path / "mocap-validation"
    done = in_process(
        "validate", str(session), "--path", VALIDATION_PATH, "--trials", "2",
        "--port", "fakerobot://?seed=1&time_scale=2000", "--measure", "tcp://127.0.0.1:9",
        "--out", str(out),
    )  # fmt: skip
    assert done.returncode == 2, done.stdout + done.stderr
    assert "[measurement] pose_sigma" in done.stderr
    assert not out.exists()


def test_detect_sizes_the_driven_validation_before_anything_moves(
    session: Path, tmp_path: Path
) -> None:
    """``--detect E_R=0.4`` (deg/m) chooses the trials, printed before the
    validation session opens; a path that cannot catch the error is refused
    (exit 2) with nothing driven (issue 31; the sizing itself:
    tests/session/test_validation_sizing.py)."""
    out = tmp_path / "sized"
    port = ["--port", "fakerobot://?seed=7&time_scale=2000", "--measure", "fake", "--seed", "7"]
    done = in_process(
        "validate", str(session), "--path", VALIDATION_PATH, "--detect", "E_R=0.4", *port,
        "--out", str(out), "--json",
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    data = json.loads(done.stdout)
    assert data["n_trials"] == data["sizing"]["trials"] >= 1
    assert data["sizing"]["detect"]["E_R"]["power"] >= 0.9
    planned = f"trials: {data['n_trials']} of {VALIDATION_PATH} (planned by --detect)"
    said = " ".join(done.stderr.split())
    assert said.index(planned) < said.index("validation session")
    refused = in_process(
        "validate", str(session), "--path", VALIDATION_PATH, "--detect", "E_R=0.001", *port,
        "--out", str(tmp_path / "never"),
    )  # fmt: skip
    assert refused.returncode == 2, refused.stderr
    message = " ".join(refused.stderr.split())
    assert "cannot catch E_R off by 0.001 deg/m with probability 0.9 in 10000 trials" in message
    assert not (tmp_path / "never").exists()
