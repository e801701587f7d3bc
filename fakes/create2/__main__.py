"""``python -m fakes.create2``: the fake iRobot Create 2 on a pty."""

from __future__ import annotations

import argparse
import logging

from fakes.create2.config import (
    CREATE2_TRUTH,
    DEFAULT_SPIN_K,
    DEFAULT_TURN_SCALE,
    FAULT_NAMES,
    build_config,
)
from fakes.create2.run import run_emulator
from odohil.protocol.create2.opcodes import DEFAULT_BAUD
from odohil.science.parameters import ErrorParameters


def main(argv: list[str] | None = None) -> None:
    """Parse the options and serve until SIGINT/SIGTERM."""
    paper = CREATE2_TRUTH.to_paper_units()
    parser = argparse.ArgumentParser(prog="python -m fakes.create2", description=__doc__)
    parser.add_argument("--seed", type=int, default=None)
    parser.add_argument("--E-R", dest="e_r", type=float, default=paper["E_R"], help="deg/m")
    parser.add_argument("--E-T", dest="e_t", type=float, default=paper["E_T"], help="no unit")
    parser.add_argument("--K-theta", dest="k_theta", type=float, default=paper["K_theta"])
    parser.add_argument("--K-rho", dest="k_rho", type=float, default=paper["K_rho"], help="m")
    parser.add_argument("--turn-scale", type=float, default=DEFAULT_TURN_SCALE)
    parser.add_argument("--spin-k", type=float, default=DEFAULT_SPIN_K, help="rad^2/rad")
    parser.add_argument("--time-scale", type=float, default=1.0)
    parser.add_argument("--baud", type=int, default=DEFAULT_BAUD)
    parser.add_argument(
        "--fault", action="append", default=[], help=f"NAME[@METRES], NAME one of {FAULT_NAMES}"
    )
    parser.add_argument("--encoder-origin", type=int, default=0)
    parser.add_argument("--mode-offset", type=int, default=0)
    parser.add_argument("--angle-bug", action="store_true")
    parser.add_argument("--truth-socket", default=None)
    parser.add_argument("--no-pacing", action="store_true")
    parser.add_argument("--verbose", action="store_true")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO if args.verbose else logging.WARNING)
    config = build_config(
        seed=args.seed,
        params=ErrorParameters.from_paper_units(args.e_r, args.e_t, args.k_theta, args.k_rho),
        turn_scale=args.turn_scale,
        spin_k=args.spin_k,
        time_scale=args.time_scale,
        baud=args.baud,
        faults=args.fault,
        encoder_origin=args.encoder_origin,
        mode_offset=args.mode_offset,
        angle_bug=args.angle_bug,
    )
    run_emulator(config, pacing=not args.no_pacing, truth_socket=args.truth_socket)


if __name__ == "__main__":
    main()
