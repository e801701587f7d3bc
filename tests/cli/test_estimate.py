"""``odohil estimate`` run as the real console command on files made by ``odohil simulate``."""

from __future__ import annotations

import json
import math
import subprocess
from pathlib import Path

import pytest

from odohil.science.parameters import NOMAD150
from tests import forked


def run(*args: str | Path) -> subprocess.CompletedProcess[str]:
    # a process of its own, forked from a server that imported odohil once (tests/forked.py)
    return forked.completed(["odohil", *map(str, args)], timeout=120)


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


@pytest.mark.parametrize("method", ["robust", "joint", "paper"])
def test_json_output_recovers_the_simulated_parameters(trial_file: Path, method: str) -> None:
    done = run("estimate", trial_file, "--method", method, "--json")
    assert done.returncode == 0, done.stderr
    data = json.loads(done.stdout)
    assert data["verdict"] == {"status": "trusted", "reasons": []}
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
    for text in ("E_R", "K_theta", "deg/m", "deg^2/m", "model check:", "sufficiency:"):
        assert text in done.stdout
    # before: paper and SI columns side by side, E_T's unit printed as "1"
    assert "rad/m" not in done.stdout
    assert "(no unit)" in done.stdout


def _row(table: str, name: str) -> list[str]:
    line = next(line for line in table.splitlines() if line.strip("│┃ ").startswith(name + " "))
    return [cell.strip() for cell in line.strip("│┃ ").split("│")]


def test_units_si_prints_the_json_values_and_paper_converts_them(trial_file: Path) -> None:
    data = json.loads(run("estimate", trial_file, "--json").stdout)["parameters"]
    si = run("estimate", trial_file, "--units", "si")
    paper = run("estimate", trial_file, "--units", "paper")
    assert si.returncode == paper.returncode == 0, si.stderr
    assert "rad/m" in si.stdout
    assert "rad^2/m" in si.stdout
    assert "deg/m" not in si.stdout
    assert paper.stdout == run("estimate", trial_file).stdout  # paper is the default
    for name, factor in (("E_R", 180 / math.pi), ("K_theta", (180 / math.pi) ** 2)):
        assert float(_row(si.stdout, name)[1]) == pytest.approx(data[name]["value"], rel=1e-3)
        shown = float(_row(paper.stdout, name)[1])
        assert shown == pytest.approx(data[name]["value"] * factor, rel=1e-3)
    assert _row(paper.stdout, "E_T")[4] == "(no unit)"


def _shifted(trial_file: Path, folder: Path, row: int, dx: float, dy: float) -> Path:
    """The trial file with trial ``row`` (1-based) moved by (dx, dy) metres."""
    lines = trial_file.read_text().splitlines()
    k, l_m, variant, x, y, dtheta = lines[row].split(",")
    lines[row] = ",".join([k, l_m, variant, str(float(x) + dx), str(float(y) + dy), dtheta])
    bad = folder / "outlier.csv"
    bad.write_text("\n".join(lines) + "\n")
    return bad


def test_outlier_is_named_by_trial_number_and_design(trial_file: Path, tmp_path: Path) -> None:
    bad = _shifted(trial_file, tmp_path, 4, 0.2, 0.0)
    done = run("estimate", bad, "--json")
    assert done.returncode == 3, done.stderr
    data = json.loads(done.stdout)
    assert [(o["trial"], o["design"]) for o in data["model_check"]["outliers"]] == [
        (4, "k=1 l=6 m turn")
    ]
    assert data["verdict"]["status"] == "doubtful"
    assert "trial 4 (k=1 l=6 m turn)" in data["verdict"]["reasons"][0]


def test_a_5_cm_slip_in_one_design_b_trial_is_named_and_the_estimate_holds(
    trial_file: Path, tmp_path: Path
) -> None:
    """Issue 8: 5 cm on one design-B trial's y moved the Gaussian fit's K_theta
    by many standard errors while the goodness-of-fit test stayed quiet."""
    bad = _shifted(trial_file, tmp_path, 45, 0.0, 0.05)  # trial 45: the 15th of design B
    truth = NOMAD150.to_si_dict()
    gaussian = json.loads(run("estimate", bad, "--method", "joint", "--json").stdout)
    entry = gaussian["parameters"]["K_theta"]
    assert abs(entry["value"] - truth["K_theta"]) > 4 * entry["stderr"]
    done = run("estimate", bad, "--json")
    assert done.returncode == 3, done.stderr
    data = json.loads(done.stdout)
    for name, entry in data["parameters"].items():
        assert entry["ci95"][0] <= truth[name] <= entry["ci95"][1], name
    assert [o["trial"] for o in data["model_check"]["outliers"]] == [45]
    assert "gaussian_ml" in data
    influence = {t["trial"]: abs(t["influence"]["K_theta"]) for t in data["trials"]}
    assert max(influence, key=lambda t: influence[t]) == 45
    excluded = run("estimate", bad, "--exclude", "45", "--json")
    assert excluded.returncode == 0, excluded.stdout
    kept = json.loads(excluded.stdout)
    assert kept["excluded"] == [45]
    assert kept["n_trials"] == 59
    assert kept["verdict"]["status"] == "trusted"


@pytest.mark.parametrize("value", ["99", "0", "3,x"])
def test_bad_exclude_exits_2_naming_the_option(trial_file: Path, value: str) -> None:
    done = run("estimate", trial_file, "--exclude", value)
    assert done.returncode == 2
    assert "--exclude" in done.stderr


def test_degenerate_data_fail_with_exit_3(tmp_path: Path) -> None:
    rows = ["k,l_m,variant,dx_m,dy_m,dtheta_rad"]
    rows += ["1,6,turn,0.01,0.1,-0.04"] * 30 + ["20,0.5,turn,0.002,0.01,-0.07"] * 30
    same = tmp_path / "same.csv"
    same.write_text("\n".join(rows) + "\n")
    done = run("estimate", same, "--json")
    assert done.returncode == 3, done.stderr
    data = json.loads(done.stdout)
    assert data["verdict"]["status"] == "failed"
    assert any("degenerate" in r for r in data["verdict"]["reasons"])
    table = run("estimate", same)
    assert table.returncode == 3
    assert "verdict: FAILED" in table.stdout


def test_bad_file_exits_2_with_line_numbers(tmp_path: Path) -> None:
    bad = tmp_path / "bad.csv"
    bad.write_text("k,l_m,variant,dx_m,dy_m,dtheta_rad\n1,6,turn,0.1,abc,0\n1,-6,turn,0,0,0\n")
    done = run("estimate", bad)
    assert done.returncode == 2
    assert "line 2" in done.stderr
    assert "line 3" in done.stderr


def test_too_few_trials_is_no_estimate_exit_3(tmp_path: Path) -> None:
    """No estimate is "not trusted or no estimate" (exit 3), as report and export say."""
    one = tmp_path / "one.csv"
    one.write_text("k,l_m,variant,dx_m,dy_m,dtheta_rad\n1,6,turn,0.01,0.1,-0.04\n")
    done = run("estimate", one)
    assert done.returncode == 3
    assert "NO ESTIMATE" in done.stdout
    assert "at least 2 trials" in " ".join(done.stdout.split())


def test_missing_file_exits_2(tmp_path: Path) -> None:
    done = run("estimate", tmp_path / "nope.csv")
    assert done.returncode == 2
