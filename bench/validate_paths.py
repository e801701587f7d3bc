"""Issue 19, acceptance 1 over several seeds: ``odohil validate --path
square:1.0,cw|ccw --trials 15 --measure fake`` passes (exit 0) on the fake a
session was calibrated on and fails (exit 3) on one whose E_R is three times
and K_theta nine times larger, for the fake Nomad and the fake Create 2.

Per robot and seed: one calibration by ``odohil run`` on the robot's fake
(the Nomad: the README's robot and tests/cli/test_validate.py's plan; the
Create 2: the built-in description, turns_exact = false, straight runs and
polygonal circles both ways, so e_turn and K_spin are fitted), then four
validations (cw, ccw x calibrated, wrong fake) with other draws (seed + 100).
Each command runs as a user runs it (``python -m odohil``); ``--jobs`` runs
that many seeds at once.

Run: nice -n 10 python bench/validate_paths.py [--seeds 1-5] [--robot nomad150 --robot create2]
[--jobs 2]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from tests.cli.test_validate_paths import ROBOTS  # noqa: E402
from tests.session.test_trust_runs import readme_robot  # noqa: E402

DIRECTIONS = ("cw", "ccw")
MAX_RESUMES = 3
"""How often a run a loaded machine cut off is resumed, as its user would (the
Create 2's host may miss its stream for a second)."""


def odohil(*args: str) -> tuple[int, str, str]:
    done = subprocess.run(
        [sys.executable, "-m", "odohil", *args],
        capture_output=True,
        text=True,
        timeout=1800,
        check=False,
        cwd=ROOT,
    )
    return done.returncode, done.stdout, done.stderr


def resumed(code: int, err: str, folder: Path) -> tuple[int, str, int]:
    """Resume a run cut off by an error (exit 1, its session journaled) as its
    user would; (exit status, stderr, resumes)."""
    resumes = 0
    while code == 1 and "odohil resume" in err and resumes < MAX_RESUMES:
        resumes += 1
        code, _, err = odohil("resume", str(folder), "--from-here", "--json")
    return code, err, resumes


def last_error(err: str) -> str:
    lines = [line for line in err.splitlines() if line.startswith("error")]
    return lines[-1] if lines else (err.strip().splitlines() or [""])[-1]


def robot_option(robot: str, folder: Path) -> str:
    if robot == "create2":
        return "create2"
    path = folder / "robot.toml"
    path.write_text(readme_robot(), encoding="utf-8")
    return str(path)


def one_seed(robot: str, seed: int, root: Path) -> list[dict[str, object]]:
    """The calibration and the four validations of one seed."""
    folder = root / f"{robot}-{seed}"
    folder.mkdir()
    option = robot_option(robot, folder)
    session = folder / "calibration"
    started = time.monotonic()
    code, out, err = odohil(
        "run", "--allow-few-trials", "--port", ROBOTS[robot]["url"].format(seed=seed),
        "--robot", option, "--plan", ROBOTS[robot]["plan"], "--measure", "fake",
        "--seed", str(seed), "--session", str(session), "--json",
    )  # fmt: skip
    first_error = last_error(err) if code == 1 else ""
    code, err, calibration_resumes = resumed(code, err, session)
    rows: list[dict[str, object]] = []
    if code != 0:
        note = last_error(err)
        return [{"robot": robot, "seed": seed, "cell": "calibration", "exit": code, "note": note}]
    calibrated_s = time.monotonic() - started
    try:
        calibration_e_r = json.loads(out)["parameters"]["E_R"]["value"]
    except (ValueError, KeyError):
        calibration_e_r = math.nan  # resumed: the JSON is the resume's, not read here
    other = seed + 100
    for direction in DIRECTIONS:
        for fake in ("calibrated", "wrong"):
            url = ROBOTS[robot]["url"].format(seed=other)
            url += ROBOTS[robot]["wrong"] if fake == "wrong" else ""
            started = time.monotonic()
            out_folder = folder / f"{direction}-{fake}"
            args = [
                "validate", str(session), "--port", url, "--robot", option,
                "--path", f"square:1.0,{direction}", "--trials", "15", "--measure", "fake",
                "--seed", str(other), "--out", str(out_folder), "--json",
            ]  # fmt: skip
            code, out, err = odohil(*args)
            resumes, error = 0, ""
            if code == 1:
                error = last_error(err)
                code, err, resumes = resumed(code, err, out_folder)
                if code in (0, 3):
                    code, out, err = odohil(*args)
            row: dict[str, object] = {
                "robot": robot,
                "seed": seed,
                "cell": f"{direction} {fake}",
                "exit": code,
                "seconds": round(time.monotonic() - started, 1),
                "calibration_s": round(calibrated_s, 1),
                "resumes": resumes,
                "calibration_resumes": calibration_resumes,
            }
            if error or first_error:
                row["cut_off_by"] = error or first_error
            try:
                data = json.loads(out)
                verdict = data["verdict"]
                row["nees"] = round(verdict["overall"]["nees"], 1)
                row["dof"] = verdict["overall"]["dof"]
                row["failed"] = verdict["failed"]
                row["left_out"] = data["left_out_ambiguous"]
                # what a pass rules out, beside how far off the fake is (deg/m)
                found = verdict["detectable"].get("E_R", {}).get("error", math.nan)
                row["detectable_E_R_deg_m"] = round(math.degrees(found), 3)
                row["calibration_E_R_deg_m"] = round(math.degrees(calibration_e_r), 3)
            except (ValueError, KeyError):
                row["note"] = err.strip().splitlines()[-1] if err.strip() else ""
            rows.append(row)
    return rows


def seeds_of(text: str) -> list[int]:
    low, _, high = text.partition("-")
    return list(range(int(low), int(high or low) + 1))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", default="1-5", help="e.g. 1-5")
    parser.add_argument("--robot", action="append", choices=sorted(ROBOTS))
    parser.add_argument("--jobs", type=int, default=1)
    args = parser.parse_args()
    robots = args.robot or sorted(ROBOTS)
    load = os.getloadavg()
    started = time.monotonic()
    jobs = [(robot, seed) for robot in robots for seed in seeds_of(args.seeds)]
    with tempfile.TemporaryDirectory() as tmp, ThreadPoolExecutor(args.jobs) as pool:
        results = list(pool.map(lambda job: one_seed(job[0], job[1], Path(tmp)), jobs))
    rows = [row for result in results for row in result]
    for row in rows:
        print(json.dumps(row))
    print(f"\nload average before: {load[0]:.1f} {load[1]:.1f} {load[2]:.1f}; "
          f"wall time {time.monotonic() - started:.0f} s\n")  # fmt: skip
    print("| robot | direction | fake | seeds | exit 0 (pass) | exit 3 (fail) | other | resumed |")
    print("|---|---|---|---|---|---|---|---|")
    for robot in robots:
        for direction in DIRECTIONS:
            for fake in ("calibrated", "wrong"):
                cell = [
                    r for r in rows if r["robot"] == robot and r["cell"] == f"{direction} {fake}"
                ]
                codes = [r["exit"] for r in cell]
                broken = sum(1 for r in rows if r["robot"] == robot and r["cell"] == "calibration")
                other = len(codes) - codes.count(0) - codes.count(3)
                print(
                    f"| {robot} | {direction} | {fake} | {len(codes)} | {codes.count(0)} | "
                    f"{codes.count(3)} | {other}"
                    + (f" ({broken} calibration(s) failed)" if broken else "")
                    + f" | {sum(int(str(r['resumes'])) for r in cell)} |"
                )


if __name__ == "__main__":
    main()
