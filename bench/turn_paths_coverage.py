"""Issue 19, acceptance 2 over several seeds: how often does the 95 % interval
of e_turn, from a session of squares and circles (both ways) on the fake
Create 2 with a known turn-scale error, hold the fake's value?

Each seed: tests/cli/test_turn_scale_paths.py's plan run by ``odohil run`` on
``fakecreate2://?seed=S&time_scale=10&max_gap_ms=15&turn_scale=0.02`` (a run
cut off on a loaded machine resumed as its user would), then ``odohil
estimate --json``.

Run: nice -n 10 python bench/turn_paths_coverage.py [--seeds 1-6] [--jobs 1]
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))

from validate_paths import odohil, resumed, seeds_of  # noqa: E402

from tests.cli.test_turn_scale_paths import PLAN, TURN_SCALE, URL  # noqa: E402


def one_seed(seed: int, root: Path) -> dict[str, object]:
    session = root / f"turns-{seed}"
    started = time.monotonic()
    code, _, err = odohil(
        "run", "--allow-few-trials", "--robot", "create2", "--plan", PLAN,
        "--port", URL.format(seed=seed, scale=TURN_SCALE), "--measure", "fake",
        "--seed", str(seed), "--session", str(session), "--json",
    )  # fmt: skip
    code, err, resumes = resumed(code, err, session)
    row: dict[str, object] = {"seed": seed, "run_exit": code, "resumes": resumes}
    if code not in (0, 3):
        row["note"] = err.strip().splitlines()[-1] if err.strip() else ""
        return row
    code, out, err = odohil("estimate", str(session), "--json")
    data = json.loads(out)
    row["verdict"] = data["verdict"]["status"]
    names = [name for name in data["parameters"] if name.startswith("e_turn")]
    row["e_turn"] = {
        name: [round(data["parameters"][name]["value"], 5)]
        + [round(v, 5) for v in data["parameters"][name]["ci95"]]
        for name in names
    }
    row["covered"] = all(
        data["parameters"][n]["ci95"][0] <= TURN_SCALE <= data["parameters"][n]["ci95"][1]
        for n in names
    )
    row["seconds"] = round(time.monotonic() - started, 1)
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", default="1-6")
    parser.add_argument("--jobs", type=int, default=1)
    args = parser.parse_args()
    load = os.getloadavg()
    started = time.monotonic()
    with tempfile.TemporaryDirectory() as tmp, ThreadPoolExecutor(args.jobs) as pool:
        rows = list(pool.map(lambda s: one_seed(s, Path(tmp)), seeds_of(args.seeds)))
    for row in rows:
        print(json.dumps(row))
    estimated = [r for r in rows if "covered" in r]
    covered = sum(1 for r in estimated if r["covered"])
    print(
        f"\nload average before: {load[0]:.1f} {load[1]:.1f} {load[2]:.1f}; wall time "
        f"{time.monotonic() - started:.0f} s\ne_turn's 95 % interval holds {TURN_SCALE:g} in "
        f"{covered} of {len(estimated)} sessions ({len(rows) - len(estimated)} without an estimate)"
    )


if __name__ == "__main__":
    main()
