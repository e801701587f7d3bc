"""``odohil simulate``, run as the real console command."""

from __future__ import annotations

import csv
import math
import os
import shutil
import signal
import subprocess
import time
from pathlib import Path

import numpy as np
import numpy.typing as npt
import pexpect
import pytest

from odohil.cli.exit_codes import EXIT_INTERRUPTED
from odohil.science.parameters import NOMAD150
from tests import forked

ODOHIL = shutil.which("odohil") or "odohil"
ENV = {**os.environ, "COLUMNS": "160", "NO_COLOR": "1"}
Z = 4.0


def run(*args: str) -> subprocess.CompletedProcess[str]:
    # a process of its own, forked from a server that imported odohil once (tests/forked.py)
    return forked.completed([ODOHIL, "simulate", *args], 120, ENV)


def read_rows(path: Path) -> tuple[list[dict[str, str]], npt.NDArray[np.float64]]:
    with path.open(newline="") as stream:
        reader = csv.DictReader(stream)
        assert reader.fieldnames == ["k", "l_m", "variant", "dx_m", "dy_m", "dtheta_rad"]
        rows = list(reader)
    values = np.array([[float(r["dx_m"]), float(r["dy_m"]), float(r["dtheta_rad"])] for r in rows])
    return rows, values


def assert_mean(sample: npt.NDArray[np.float64], expected: float) -> None:
    se = float(sample.std(ddof=1)) / math.sqrt(sample.size)
    assert abs(float(sample.mean()) - expected) <= Z * se, (sample.mean(), expected, se)


def assert_variance(sample: npt.NDArray[np.float64], expected: float) -> None:
    """Sample variance of a normal sample: SE = var sqrt(2 / (n - 1))."""
    tolerance = Z * expected * math.sqrt(2.0 / (sample.size - 1))
    assert abs(float(sample.var(ddof=1)) - expected) <= tolerance


def test_writes_one_row_per_trial_and_nothing_on_stdout(tmp_path: Path) -> None:
    out = tmp_path / "trials.csv"
    result = run(
        "--k",
        "1.5",
        "--l",
        "0.8",
        "--trials",
        "500",
        "--seed",
        "3",
        "--out",
        str(out),
        "--variant",
        "reverse",
        "--segment-m",
        "0.01",
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout == ""
    rows, values = read_rows(out)
    assert len(rows) == 500
    assert {(r["k"], r["l_m"], r["variant"]) for r in rows} == {("1.5", "0.8", "reverse")}
    assert np.all(np.isfinite(values))
    assert [p.name for p in tmp_path.iterdir()] == ["trials.csv"]


def test_same_seed_same_file_and_full_precision(tmp_path: Path) -> None:
    args = ("--k", "1", "--l", "1", "--trials", "200", "--seed", "9", "--segment-m", "0.01")
    first, second = tmp_path / "a.csv", tmp_path / "b.csv"
    assert run(*args, "--out", str(first)).returncode == 0
    assert run(*args, "--out", str(second)).returncode == 0
    assert first.read_bytes() == second.read_bytes()
    for field in first.read_text().splitlines()[1].split(",")[3:]:
        assert repr(float(field)) == field


def test_heading_change_has_the_paper_unit_parameters(tmp_path: Path) -> None:
    """--E-R in deg/m and --K-theta in deg^2/m: Delta ~ N(E_R rho, K_theta rho)."""
    out = tmp_path / "t.csv"
    n = 4000
    result = run(
        "--k",
        "1",
        "--l",
        "2",
        "--trials",
        str(n),
        "--seed",
        "1",
        "--out",
        str(out),
        "--E-R",
        "20",
        "--K-theta",
        "200",
        "--segment-m",
        "0.02",
    )
    assert result.returncode == 0, result.stderr
    _, values = read_rows(out)
    rho = 4.0
    assert_mean(values[:, 2], math.radians(20.0) * rho)
    assert_variance(values[:, 2], 200.0 * (math.pi / 180.0) ** 2 * rho)


def test_translation_has_the_given_e_t_and_k_rho(tmp_path: Path) -> None:
    """One way (k = 1/2) with no rotation error: dx ~ N((1 + E_T) l, K_rho l)."""
    out = tmp_path / "t.csv"
    result = run(
        "--k",
        "0.5",
        "--l",
        "3",
        "--trials",
        "4000",
        "--seed",
        "2",
        "--out",
        str(out),
        "--E-R",
        "0",
        "--K-theta",
        "0",
        "--E-T",
        "-0.05",
        "--K-rho",
        "0.002",
        "--segment-m",
        "0.05",
    )
    assert result.returncode == 0, result.stderr
    _, values = read_rows(out)
    assert_mean(values[:, 0], 0.95 * 3.0)
    assert_variance(values[:, 0], 0.002 * 3.0)
    assert np.all(values[:, 1:] == 0.0)


def test_defaults_are_the_nomad150_values(tmp_path: Path) -> None:
    out = tmp_path / "t.csv"
    result = run(
        "--k",
        "0.5",
        "--l",
        "10",
        "--trials",
        "3000",
        "--seed",
        "4",
        "--out",
        str(out),
        "--segment-m",
        "0.05",
    )
    assert result.returncode == 0, result.stderr
    _, values = read_rows(out)
    assert_mean(values[:, 2], NOMAD150.e_r * 10.0)
    assert_variance(values[:, 2], NOMAD150.k_theta * 10.0)
    assert "seed" not in result.stderr  # a given seed is not reported again


def test_without_seed_reports_the_seed_it_used(tmp_path: Path) -> None:
    out, again = tmp_path / "a.csv", tmp_path / "b.csv"
    result = run("--k", "1", "--l", "1", "--trials", "50", "--segment-m", "0.1", "--out", str(out))
    assert result.returncode == 0, result.stderr
    seed = result.stderr.split("seed", 1)[1].split()[0]
    rerun = run(
        "--k",
        "1",
        "--l",
        "1",
        "--trials",
        "50",
        "--segment-m",
        "0.1",
        "--seed",
        seed,
        "--out",
        str(again),
    )
    assert rerun.returncode == 0, rerun.stderr
    assert out.read_bytes() == again.read_bytes()


BAD = {
    "k not a multiple of 1/2": ["--k", "0.3"],
    "no trials": ["--trials", "0"],
    "nan segment": ["--segment-m", "nan"],
    "negative K_theta": ["--K-theta", "-1"],
    "1 + E_T not positive": ["--E-T", "-1"],
    "unknown variant": ["--variant", "sideways"],
    "negative seed": ["--seed", "-5"],
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_input_exits_2_without_traceback_and_keeps_the_old_file(
    tmp_path: Path, case: str
) -> None:
    out = tmp_path / "t.csv"
    out.write_text("old content\n")
    options = {"--k": "1", "--l": "1", "--trials": "10", "--segment-m": "0.1"}
    bad = BAD[case]
    options[bad[0]] = bad[1]
    args = [item for pair in options.items() for item in pair]
    result = run(*args, "--out", str(out))
    assert result.returncode == 2, result.stderr
    assert "Traceback" not in result.stderr
    assert result.stderr.strip()
    assert out.read_text() == "old content\n"
    assert [p.name for p in tmp_path.iterdir()] == ["t.csv"]


def test_missing_output_folder_exits_2(tmp_path: Path) -> None:
    result = run("--k", "1", "--l", "1", "--trials", "10", "--out", str(tmp_path / "no" / "t.csv"))
    assert result.returncode == 2
    assert "Traceback" not in result.stderr
    assert "does not exist" in result.stderr


def test_long_run_shows_progress_on_stderr_and_interrupt_leaves_old_file(tmp_path: Path) -> None:
    out = tmp_path / "t.csv"
    out.write_text("old content\n")
    child = pexpect.spawn(
        ODOHIL,
        [
            "simulate",
            "--k",
            "1",
            "--l",
            "6",
            "--trials",
            "80000",
            "--seed",
            "1",
            "--out",
            str(out),
        ],
        env=ENV,
        encoding="utf-8",
        timeout=60,
    )
    child.expect("simulating")
    time.sleep(0.2)
    child.kill(signal.SIGINT)
    child.expect(pexpect.EOF)
    child.close()
    # 80,000 trials take seconds: Ctrl-C lands mid-simulation, and odohil exits 130
    assert (child.exitstatus, child.signalstatus) == (EXIT_INTERRUPTED, None)
    assert out.read_text() == "old content\n"
    assert [p.name for p in tmp_path.iterdir()] == ["t.csv"]
