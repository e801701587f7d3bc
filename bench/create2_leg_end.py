"""How far past the commanded length a Create 2 leg ends: polling vs streaming.

Starts the fake Create 2 (``python -m fakes.create2 --baud B``, line pacing on,
time scale 1) on a pty, connects the driver at B baud with ``sampling`` poll
or stream, and drives one-way legs of 0.5 m, alternately forwards and
backwards. Each leg's end is read from the fake's true encoder counts (the
side channel) against the commanded length: mm past the end (positive: too
far). The driver closes each leg on the encoders against targets counted from
the trial's start; this measures the first leg of each trial alone.

Run: nice -n 10 python bench/create2_leg_end.py [--legs 12] [--baud 115200 --baud 19200]
[--no-crawl]
"""

from __future__ import annotations

import argparse
import math
import os
import statistics
import time

import odohil.driver.create2.robot as create2_robot
from fakes.create2.process import Create2Process
from odohil.driver.create2.link import SAMPLINGS, Sampling
from odohil.driver.create2.robot import Create2Robot
from odohil.driver.odometry import DriveSettings
from odohil.errors import MotionError
from odohil.protocol.create2.geometry import CREATE2_GEOMETRY
from odohil.science.paths import Design

LEG_M = 0.5


def measure(
    baud: int, sampling: Sampling, legs: int, speed: float, flagged: list[int]
) -> tuple[list[float], float]:
    """Overshoot of each leg, mm, and the mean number of readings per second;
    ``flagged[0]`` counts the legs the driver refused (MotionError)."""
    geometry = CREATE2_GEOMETRY
    mm_per_count = geometry.metres_per_count * 1000.0
    settings = DriveSettings(speed_m_s=speed, step_timeout_s=30.0)
    overshoot: list[float] = []
    with Create2Process(["--seed", "1", "--baud", str(baud)]) as fake:
        robot = Create2Robot.connect(fake.device, baud=baud, sampling=sampling, open_wait_s=0.2)
        with robot:
            robot.arm(settings)
            started, readings0 = time.monotonic(), robot.link.readings
            for index in range(legs):
                backward = index % 2 == 1
                before = fake.truth().left_counts
                try:
                    robot.drive(Design(0.5, LEG_M, backward=backward), settings)
                except MotionError:
                    flagged[0] += 1  # beyond the step tolerance: measured all the same
                    time.sleep(0.1)
                after = fake.truth().left_counts
                moved_mm = (after - before) * mm_per_count * (-1 if backward else 1)
                overshoot.append(moved_mm - LEG_M * 1000.0)
            rate = (robot.link.readings - readings0) / (time.monotonic() - started)
    return overshoot, rate


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--legs", type=int, default=12)
    parser.add_argument("--speed", type=float, default=0.3, help="m/s")
    parser.add_argument("--baud", type=int, action="append")
    parser.add_argument(
        "--no-crawl", action="store_true", help="stop from full speed (no slow final approach)"
    )
    args = parser.parse_args()
    if args.no_crawl:
        create2_robot.CRAWL_MM_S = 500
    approach = "no crawl" if args.no_crawl else f"crawl {create2_robot.CRAWL_MM_S} mm/s"
    print(f"load {os.getloadavg()[0]:.2f}; legs of {LEG_M} m at {args.speed} m/s, {approach}")
    print("baud    sampling  mean mm  sd mm  max |mm|  readings/s  refused")
    for baud in args.baud or [115200, 19200]:
        for sampling in SAMPLINGS:
            flagged = [0]
            over, rate = measure(baud, sampling, args.legs, args.speed, flagged)
            worst = max(abs(v) for v in over)
            sd = statistics.stdev(over) if len(over) > 1 else math.nan
            print(
                f"{baud:<7} {sampling:<8} {statistics.mean(over):+8.2f} {sd:6.2f} "
                f"{worst:9.2f} {rate:10.1f}  {flagged[0]:7d}"
            )


if __name__ == "__main__":
    main()
