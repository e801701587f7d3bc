"""``python -m fakes.create2``: the fake iRobot Create 2 on a pty."""

from __future__ import annotations

import argparse

from fakes.create2.config import (
    CREATE2_TRUTH,
    DEFAULT_MODE_CHANGE_S,
    DEFAULT_SPIN_K,
    DEFAULT_TURN_SCALE,
    FAULT_NAMES,
    HOST_BOUND_S,
    PASSIVE_SLEEP_S,
    build_config,
    parse_fault,
)
from fakes.create2.run import run_emulator
from fakes.launch import add_serving_options, add_truth_options, checked_by, parse_and_log
from odohil.protocol.create2.opcodes import DEFAULT_BAUD
from odohil.science.parameters import ErrorParameters


def main(argv: list[str] | None = None) -> None:
    """Parse the options and serve until SIGINT/SIGTERM."""
    parser = argparse.ArgumentParser(prog="python -m fakes.create2", description=__doc__)
    add_truth_options(parser, CREATE2_TRUTH)
    parser.add_argument("--turn-scale", type=float, default=DEFAULT_TURN_SCALE)
    parser.add_argument("--spin-k", type=float, default=DEFAULT_SPIN_K, help="rad^2/rad")
    parser.add_argument("--time-scale", type=float, default=1.0)
    parser.add_argument("--baud", type=int, default=DEFAULT_BAUD)
    parser.add_argument(
        "--fault",
        action="append",
        default=[],
        type=checked_by(parse_fault),
        help=f"NAME[@METRES], NAME one of {FAULT_NAMES}",
    )
    parser.add_argument("--encoder-origin", type=int, default=0)
    parser.add_argument("--mode-offset", type=int, default=0)
    parser.add_argument("--angle-bug", action="store_true")
    parser.add_argument(
        "--mode-change-ms",
        type=float,
        default=DEFAULT_MODE_CHANGE_S * 1000.0,
        help="wall ms a Safe or Full command takes to take effect",
    )
    parser.add_argument(
        "--passive-sleep-s",
        type=float,
        default=PASSIVE_SLEEP_S,
        help="simulated s in Passive without a command before it sleeps (0: never)",
    )
    parser.add_argument(
        "--host-bound-ms",
        type=float,
        default=HOST_BOUND_S * 1000.0,
        help="wall ms the motion runs past what the host has read (0: no bound)",
    )
    add_serving_options(parser)
    args = parse_and_log(parser, argv)
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
        mode_change_s=args.mode_change_ms / 1000.0,
        passive_sleep_s=args.passive_sleep_s or None,
    )
    run_emulator(
        config,
        pacing=not args.no_pacing,
        truth_socket=args.truth_socket,
        host_bound_s=args.host_bound_ms / 1000.0 or None,
    )


if __name__ == "__main__":
    main()
