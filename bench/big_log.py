"""How long ``odohil estimate`` takes on a big log, and how much memory (issue 30).

Builds, in a temporary folder, a log of the optiodom June data written seven
times over, each copy's trials with their own labels (``c1/<session>_run-NN``
...), as an odohil log CSV with a ``trial`` column
(odohil/session/trials/logs/optiodom.py joined_runs, csv_log.py write_csv_log) and,
with ``--optiodom``, as an optiodom folder of seven copies of the sessions.
Per copy: all 32 circles (the long encoder paths: two or three laps, 43-64
legs) and the 14 straight runs, so 46 trials: 322 trials and 505k rows in all
(the issue's log: 434 trials, 476k rows). With ``--spins`` (the first 30
ivanjko runs with every circle: 434 trials, 553k rows) the fit of this robot
does not converge (the spins' centre drift, docs/recording.md; still so after
joint_estimate's rescue change, BENCHMARKS.md) and the robust fit runs to its
step limit: that measures the step limit, not the reading or the moments.
With ``--issue-size`` (20 circles and 42 straight runs a copy, the 14 cycled)
the log is the issue's size, 434 trials and 480k rows, of paths the model fits.

Then runs the real command, a child process of the CLI as a user starts it
(the process is the point: its start-up, its reading, its memory)::

    odohil estimate LOG --robot docs/examples/optiodom.toml --json

and prints its wall time, its CPU time (user + system: the machine is shared,
wall time counts the others' load) and its peak resident memory (the child's
``ru_maxrss``), with the machine's load (``uptime``) before and after.

    python bench/big_log.py [--data ../shared/data/optiodom-june] [--repeat 3]
        [--copies 7] [--spins | --issue-size] [--optiodom] [--keep DIR]
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from odohil.session.robots.description import load_robot_description
from odohil.session.trials.logs.csv_log import write_csv_log
from odohil.session.trials.logs.optiodom import joined_runs, read_run, run_files
from odohil.session.trials.logs.recording import ImportOptions, Recording, trials_of

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_DATA = Path(os.environ.get("ODOHIL_OPTIODOM", ROOT.parent / "shared/data/optiodom-june"))
ROBOT = ROOT / "docs/examples/optiodom.toml"


def one_copy(data: Path, spins: bool = False, issue_size: bool = False) -> list[Path]:
    """The run files of one copy: every circle and every straight run (the
    ivanjko runs the reader finds ``straight``; the others are spins), or with
    ``spins`` every circle and the first 30 ivanjko runs, spins included (62
    trials a copy: the issue's 434 trials for seven copies), or with
    ``issue_size`` the first 20 circles and 42 straight runs (the 14 cycled):
    62 trials and 68.6k rows a copy: 434 trials and 480k rows
    for seven copies (the issue's 434 trials and 476k rows), of the paths the model fits."""
    description = load_robot_description(ROBOT)
    ivanjko = run_files([data / "ivanjko"])
    circles = run_files([data / "circular"])
    if spins:
        return circles + ivanjko[:30]
    straight = [
        run
        for run in ivanjko
        if trials_of(read_run(run), description, ImportOptions())[0].family == "straight"
    ]
    if issue_size:
        return circles[:20] + [straight[i % len(straight)] for i in range(42)]
    return circles + straight


def big_recording(
    data: Path, copies: int, spins: bool = False, issue_size: bool = False
) -> Recording:
    """``copies`` copies of :func:`one_copy` as one recording, the labels of
    copy c prefixed ``cC/``, times running on."""
    base = joined_runs(one_copy(data, spins, issue_size))
    assert base.trial is not None
    base = replace(base, trial=tuple(_repeats_labelled(base.trial)))
    span = float(base.t_s[-1] - base.t_s[0]) + 0.05
    times: list[np.ndarray] = []
    labels: list[str] = []
    for c in range(copies):
        times.append(base.t_s + c * span)
        labels.extend(f"c{c + 1}/{label}" if label else "" for label in base.trial)
    t = np.concatenate(times)
    return Recording(
        source="big.csv",
        t_s=t,
        odometry=np.tile(base.odometry, (copies, 1)),
        truth=np.tile(base.truth, (copies, 1)),
        where=np.arange(2, 2 + len(t), dtype=np.int64),
        trial=tuple(labels),
    )


def _repeats_labelled(labels: tuple[str, ...]) -> list[str]:
    """The labels with a run that comes again (``issue_size``'s cycled
    straight runs) told apart: its k-th repeat labelled ``<label>#k``."""
    seen: dict[str, int] = {}
    out: list[str] = []
    previous = None
    for label in labels:
        if label and label != previous:
            seen[label] = seen.get(label, -1) + 1
        previous = label
        out.append(f"{label}#{seen[label]}" if label and seen[label] else label)
    return out


def optiodom_copies(data: Path, copies: int, folder: Path, spins: bool = False) -> Path:
    """``copies`` copies of :func:`one_copy`'s sessions as an optiodom folder
    (session names given a copy digit, the metadata's run count fixed)."""
    runs = one_copy(data, spins)
    sessions: dict[Path, list[Path]] = {}
    for run in runs:
        sessions.setdefault(run.parent, []).append(run)
    for c in range(copies):
        for session, files in sessions.items():
            name = f"{session.name}{c + 1}"
            target = folder / f"copy{c + 1}" / name
            target.mkdir(parents=True)
            meta = (session / f"{session.name}_metadata.csv").read_text(encoding="utf-8")
            lines = [
                f"N,{len(files)}" if line.split(",")[0].strip() == "N" else line
                for line in meta.splitlines()
            ]
            (target / f"{name}_metadata.csv").write_text("\n".join(lines) + "\n", "utf-8")
            for i, run in enumerate(files, start=1):
                shutil.copyfile(run, target / f"{name}_run-{i:02d}.csv")
    return folder


def uptime() -> str:
    """The machine's load."""
    return subprocess.run(["uptime"], capture_output=True, text=True, check=False).stdout.strip()


def measure(arguments: list[str]) -> tuple[float, float, float, int]:
    """(wall s, CPU s, peak RSS MB, exit status) of one run of the CLI."""
    odohil = Path(sys.executable).with_name("odohil")
    command = [str(odohil), *arguments]
    start = time.perf_counter()
    child = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    _, status, usage = os.wait4(child.pid, 0)
    wall = time.perf_counter() - start
    child.returncode = os.waitstatus_to_exitcode(status)
    error = child.stderr.read().decode() if child.stderr else ""
    if child.stderr:
        child.stderr.close()
    if child.returncode not in (0, 3):
        print(error, file=sys.stderr)
    return wall, usage.ru_utime + usage.ru_stime, usage.ru_maxrss / 1024.0, child.returncode


def report(label: str, arguments: list[str], repeat: int) -> None:
    """Run the command ``repeat`` times and print each run's figures."""
    print(f"{label}: odohil {' '.join(arguments)}")
    for _ in range(repeat):
        wall, cpu, rss, status = measure(arguments)
        print(f"    wall {wall:6.2f} s  CPU {cpu:6.2f} s  peak RSS {rss:6.1f} MB  exit {status}")


def main() -> None:
    """Build the log, run the command, print the figures."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, default=DEFAULT_DATA)
    parser.add_argument("--copies", type=int, default=7)
    parser.add_argument("--repeat", type=int, default=1)
    parser.add_argument("--optiodom", action="store_true", help="also as an optiodom folder")
    parser.add_argument(
        "--spins",
        action="store_true",
        help="circles and the first 30 ivanjko runs, spins included (434 trials for 7 copies)",
    )
    parser.add_argument(
        "--issue-size",
        action="store_true",
        help="20 circles and 42 straight runs a copy (434 trials, 480k rows for 7 copies)",
    )
    parser.add_argument("--keep", type=Path, help="build the log here and keep it")
    args = parser.parse_args()
    print(f"load before: {uptime()}")
    folder = Path(tempfile.mkdtemp(prefix="odohil-big-")) if args.keep is None else args.keep
    folder.mkdir(parents=True, exist_ok=True)
    try:
        log = folder / "big.csv"
        recording = big_recording(args.data, args.copies, args.spins, args.issue_size)
        write_csv_log(log, recording)
        assert recording.trial is not None
        trials = len(set(recording.trial) - {""})
        megabytes = log.stat().st_size / 1e6
        print(f"log: {len(recording.t_s)} rows, {trials} trials, {megabytes:.1f} MB")
        del recording
        common = ["--robot", str(ROBOT), "--json"]
        report("CSV log", ["estimate", str(log), *common], args.repeat)
        if args.optiodom:
            runs = optiodom_copies(args.data, args.copies, folder / "optiodom", args.spins)
            report("optiodom folder", ["estimate", str(runs), *common], args.repeat)
    finally:
        if args.keep is None:
            shutil.rmtree(folder)
    print(f"load after: {uptime()}")


if __name__ == "__main__":
    main()
