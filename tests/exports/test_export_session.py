"""Acceptance: each export of a session made with the fake robot, read as its consumer reads it."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

from odohil.science.estimators import EstimateResult
from odohil.science.exports import Linearisation
from odohil.session.results.exports import FILE_NAMES, export_files, export_text, write_exports
from odohil.session.results.outcome import estimate_path
from tests import forked
from tests.report.session_factory import build_session

PLAN = "k=1,l=2,n=6;k=4,l=0.5,n=6"


@pytest.fixture(scope="module")
def session(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("exports") / "session"
    build_session(folder, PLAN, seed=5)
    return folder


@pytest.fixture(scope="module")
def bumped(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Trial 3's end marks 5 cm across the path: an outlier, so doubtful."""
    folder = tmp_path_factory.mktemp("exports-bumped") / "session"
    build_session(folder, PLAN, seed=5, bump=(3, 0.05))
    return folder


@pytest.fixture(scope="module")
def estimate_of_session(session: Path) -> EstimateResult:
    result = estimate_path(session).result
    assert result is not None
    # doubtful for its 6 trials a design alone (below the planner's 10): exported with --force
    assert [r.split(":")[0] for r in result.verdict.reasons] == [
        "fewer than 10 trials a design, the planner's minimum for honest intervals"
    ], result.verdict
    return result


def _export(*args: str) -> subprocess.CompletedProcess[str]:
    # a process of its own, forked from a server that imported odohil once (tests/forked.py)
    return forked.completed(["odohil", "export", *args], timeout=120)


def _psd_matrix(values: list[Any], size: int) -> np.ndarray:
    """The row-major matrix of ``values``: all floats, symmetric, positive
    semi-definite, with a positive diagonal."""
    assert len(values) == size * size
    assert all(isinstance(v, float) for v in values)
    m = np.array(values).reshape(size, size)
    np.testing.assert_array_equal(m, m.T)
    assert np.linalg.eigvalsh(m).min() >= -1e-12 * np.abs(m).max()
    assert np.diag(m).min() > 0
    return m


def _ros_parameters(document: dict[str, Any], node: str) -> dict[str, Any]:
    """A ROS 2 parameter file: node -> ros__parameters -> values, every node so."""
    for name, body in document.items():
        assert set(body) == {"ros__parameters"}, name
    return dict(document[node]["ros__parameters"])


def test_every_export_is_read_as_its_consumer_reads_it(
    estimate_of_session: EstimateResult, tmp_path: Path
) -> None:
    result = estimate_of_session
    p = result.params
    paths = write_exports(result, tmp_path, source="session")
    assert sorted(x.name for x in paths) == sorted(FILE_NAMES.values())

    text = (tmp_path / "ros2_diff_drive.yaml").read_text()
    dd = _ros_parameters(yaml.safe_load(text), "diff_drive_controller")
    for key in ("pose_covariance_diagonal", "twist_covariance_diagonal"):
        assert len(dd[key]) == 6
        assert all(isinstance(v, float) and v > 0 for v in dd[key])
    assert dd["publish_rate"] == 50.0
    assert "speed 0.5 m/s" in text
    meta = _ros_parameters(yaml.safe_load(text), "odohil_export")
    assert meta["speed_m_per_s"] == 0.5
    assert meta["step_m"] == 0.01
    assert meta["verdict"] == "doubtful"  # its 6 trials a design

    odo = yaml.safe_load((tmp_path / "odometry_msg.yaml").read_text())
    m = _psd_matrix(odo["pose"]["covariance"], 6)
    step = odo["per_step_formula"]["step_m"]
    assert m[0, 0] == pytest.approx(p.k_rho * step)
    assert m[5, 5] == pytest.approx(p.k_theta * step)
    assert odo["per_step_formula"]["x_variance_m2_per_m"] == pytest.approx(p.k_rho)

    text = (tmp_path / "robot_localization.yaml").read_text()
    rl = _ros_parameters(yaml.safe_load(text), "ekf_filter_node")
    q = _psd_matrix(rl["process_noise_covariance"], 15)
    assert q[5, 5] == pytest.approx(p.k_theta * 0.5)
    assert "Per second at speed v = 0.5 m/s" in text

    amcl = _ros_parameters(yaml.safe_load((tmp_path / "amcl.yaml").read_text()), "amcl")
    for n in range(1, 6):
        assert isinstance(amcl[f"alpha{n}"], float)
        assert amcl[f"alpha{n}"] > 0
    assert amcl["alpha3"] == pytest.approx(p.k_rho / amcl["update_min_d"])
    assert amcl["robot_model_type"] == "nav2_amcl::DifferentialMotionModel"

    doc = json.loads((tmp_path / "odometry_model.json").read_text())
    assert doc["units"] == "SI"
    assert doc["verdict"] == result.verdict.to_json_dict()  # doubtful: 6 trials a design
    assert doc["parameter_covariance"]["order"] == ["E_R", "E_T", "K_theta", "K_rho"]
    cov = _psd_matrix([v for row in doc["parameter_covariance"]["matrix"] for v in row], 4)
    assert np.sqrt(cov[1, 1]) == pytest.approx(doc["parameters"]["E_T"]["stderr"], rel=1e-6)
    assert doc["corrections"]["distance_scale"]["value"] == pytest.approx(1 + p.e_t)
    assert doc["corrections"]["heading_drift_rad_per_m"]["value"] == pytest.approx(p.e_r)
    _psd_matrix([v for row in doc["per_step"]["covariance"] for v in row], 3)


def test_the_command_writes_what_the_report_writes(
    session: Path, estimate_of_session: EstimateResult, tmp_path: Path
) -> None:
    out = tmp_path / "rl.yaml"
    args = ("--format", "robot-localization", "--speed", "0.8", "--out", str(out))
    refused = _export(str(session), *args)  # 6 trials a design, below the planner's 10
    assert refused.returncode == 3, refused.stderr
    assert "fewer than 10 trials a design" in " ".join(refused.stderr.split())
    assert not out.exists()
    run = _export(str(session), *args, "--force")
    assert run.returncode == 0, run.stderr
    lin = Linearisation(speed_m_per_s=0.8)
    assert out.read_text() == export_text(
        "robot-localization", estimate_of_session, lin, source=session.name
    )
    printed = _export(str(session), "--format", "json", "--force")
    assert printed.returncode == 0, printed.stderr
    assert json.loads(printed.stdout)["verdict"]["status"] == "doubtful"


def test_an_untrusted_estimate_is_refused_unless_forced(bumped: Path, tmp_path: Path) -> None:
    out = tmp_path / "amcl.yaml"
    run = _export(str(bumped), "--format", "amcl", "--out", str(out))
    assert run.returncode == 3, run.stderr
    assert "DOUBTFUL" in run.stderr
    assert "outliers: trial 3" in run.stderr.replace("\n", " ")
    assert "--force" in run.stderr
    assert not out.exists()
    forced = _export(str(bumped), "--format", "amcl", "--out", str(out), "--force")
    assert forced.returncode == 0, forced.stderr
    text = out.read_text()
    assert text.startswith("# WARNING: this estimate is DOUBTFUL; exported with --force.")
    meta = _ros_parameters(yaml.safe_load(text), "odohil_export")
    assert meta["verdict"] == "doubtful"
    assert "trial 3" in meta["verdict_reasons"]


@pytest.mark.parametrize(
    ("args", "named"),
    [
        (("--format", "amcl", "--speed", "0"), "--speed must be at least 0.01"),
        (("--format", "amcl", "--rate-hz", "-5"), "--rate-hz must be at least 0.1"),
        (("--format", "yaml"), "--format"),
    ],
)
def test_bad_input_exits_2_naming_the_option(  # every option: tests/fuzz/test_cli_fuzz.py
    tmp_path: Path, args: tuple[str, ...], named: str
) -> None:
    run = _export(str(tmp_path), *args)
    assert run.returncode == 2
    assert named in " ".join(run.stderr.replace("│", " ").split())


def test_the_report_writes_the_same_files_beside_its_page(
    session: Path, estimate_of_session: EstimateResult, tmp_path: Path
) -> None:
    """What ``odohil report`` does with them:
    ``write_report(..., extra_exports=export_files(...))``."""
    from odohil.session.results.report import load_report, write_report

    data = load_report(session)
    assert data.result is not None
    written = write_report(data, tmp_path, export_files(data.result, source=session.name))
    names = {p.name for p in written}
    assert set(FILE_NAMES.values()) <= names
    page = (tmp_path / "index.html").read_text()
    assert "robot_localization.yaml" in page
    assert (tmp_path / "amcl.yaml").read_text() == export_text(
        "amcl", estimate_of_session, source=session.name
    )
