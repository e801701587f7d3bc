"""``odohil estimate`` run as the real console command on files made by ``odohil simulate``."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import pytest

from odohil.science.parameters import NOMAD150


def run(*args: str | Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        ["odohil", *map(str, args)], capture_output=True, text=True, timeout=120, check=False
    )


@pytest.fixture(scope="module")
def trial_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("estimate")
    parts = []
    for k, l_m, seed in (("1", "6", "1"), ("20", "0.5", "2")):
        out = folder / f"k{k}.csv"
        done = run(
            "simulate",
            "--k",
            k,
            "--l",
            l_m,
            "--trials",
            "30",
            "--out",
            out,
            "--seed",
            seed,
            "--segment-m",
            "0.01",
        )
        assert done.returncode == 0, done.stderr
        parts.append(out.read_text().splitlines())
    combined = folder / "ab.csv"
    combined.write_text("\n".join(parts[0] + parts[1][1:]) + "\n")
    return combined


@pytest.mark.parametrize("method", ["joint", "paper"])
def test_json_output_recovers_the_simulated_parameters(trial_file: Path, method: str) -> None:
    done = run("estimate", trial_file, "--method", method, "--json")
    assert done.returncode == 0, done.stderr
    data = json.loads(done.stdout)
    assert data["method"] == method
    assert data["n_trials"] == 60
    truth = NOMAD150.to_si_dict()
    for name, entry in data["parameters"].items():
        assert abs(entry["value"] - truth[name]) < 4 * entry["stderr"], name
        assert entry["ci95"][0] < entry["value"] < entry["ci95"][1]
    assert data["model_check"]["verdict"]
    assert data["sufficiency"]["verdict"]


def test_table_output_shows_paper_units_and_verdicts(trial_file: Path) -> None:
    done = run("estimate", trial_file)
    assert done.returncode == 0, done.stderr
    for text in ("E_R", "K_theta", "deg/m", "deg^2/m", "rad/m", "model check:", "sufficiency:"):
        assert text in done.stdout


def test_outlier_line_is_reported(trial_file: Path, tmp_path: Path) -> None:
    lines = trial_file.read_text().splitlines()
    k, l_m, variant, dx, dy, dtheta = lines[4].split(",")
    lines[4] = ",".join([k, l_m, variant, str(float(dx) + 0.2), dy, dtheta])
    bad = tmp_path / "outlier.csv"
    bad.write_text("\n".join(lines) + "\n")
    data = json.loads(run("estimate", bad, "--json").stdout)
    assert [o["line"] for o in data["model_check"]["outliers"]] == [5]


def test_bad_file_exits_2_with_line_numbers(tmp_path: Path) -> None:
    bad = tmp_path / "bad.csv"
    bad.write_text("k,l_m,variant,dx_m,dy_m,dtheta_rad\n1,6,turn,0.1,abc,0\n1,-6,turn,0,0,0\n")
    done = run("estimate", bad)
    assert done.returncode == 2
    assert "line 2" in done.stderr
    assert "line 3" in done.stderr


def test_too_few_trials_exit_2(tmp_path: Path) -> None:
    one = tmp_path / "one.csv"
    one.write_text("k,l_m,variant,dx_m,dy_m,dtheta_rad\n1,6,turn,0.01,0.1,-0.04\n")
    done = run("estimate", one)
    assert done.returncode == 2
    assert "at least 2 trials" in done.stderr


def test_missing_file_exits_2(tmp_path: Path) -> None:
    done = run("estimate", tmp_path / "nope.csv")
    assert done.returncode == 2
