"""``python -m fakes.nomad``: the fake Nomad 150 on a pty (same options as ``odohil emulate``)."""

from __future__ import annotations

import argparse

from fakes.launch import add_serving_options, add_truth_options, checked_by, parse_and_log
from fakes.nomad.config import build_config
from fakes.nomad.faults import parse_fault
from fakes.nomad.pacing import DEFAULT_BAUD
from fakes.nomad.run import run_emulator
from odohil.science.parameters import NOMAD150


def main(argv: list[str] | None = None) -> None:
    """Parse the options and serve until SIGINT/SIGTERM."""
    parser = argparse.ArgumentParser(prog="python -m fakes.nomad", description=__doc__)
    add_truth_options(parser, NOMAD150)
    parser.add_argument("--time-scale", type=float, default=1.0)
    parser.add_argument("--baud", type=int, default=DEFAULT_BAUD)
    parser.add_argument(
        "--fault", action="append", default=[], type=checked_by(parse_fault), help="NAME[:CODE][@N]"
    )
    add_serving_options(parser)
    args = parse_and_log(parser, argv)
    config = build_config(
        seed=args.seed,
        e_r_deg_per_m=args.e_r,
        e_t=args.e_t,
        k_theta_deg2_per_m=args.k_theta,
        k_rho_m=args.k_rho,
        time_scale=args.time_scale,
        faults=args.fault,
    )
    run_emulator(config, baud=args.baud, pacing=not args.no_pacing, truth_socket=args.truth_socket)


if __name__ == "__main__":
    main()
