"""``python -m fakes.nomad``: the fake Nomad 150 on a pty (same options as ``odohil emulate``)."""

from __future__ import annotations

import argparse
import logging

from fakes.nomad.config import build_config
from fakes.nomad.pacing import DEFAULT_BAUD
from fakes.nomad.run import run_emulator
from odohil.science.parameters import NOMAD150


def main(argv: list[str] | None = None) -> None:
    """Parse the options and serve until SIGINT/SIGTERM."""
    paper = NOMAD150.to_paper_units()
    parser = argparse.ArgumentParser(prog="python -m fakes.nomad", description=__doc__)
    parser.add_argument("--seed", type=int, default=None)
    parser.add_argument("--E-R", dest="e_r", type=float, default=paper["E_R"], help="deg/m")
    parser.add_argument("--E-T", dest="e_t", type=float, default=paper["E_T"], help="no unit")
    parser.add_argument(
        "--K-theta", dest="k_theta", type=float, default=paper["K_theta"], help="deg^2/m"
    )
    parser.add_argument("--K-rho", dest="k_rho", type=float, default=paper["K_rho"], help="m")
    parser.add_argument("--time-scale", type=float, default=1.0)
    parser.add_argument("--baud", type=int, default=DEFAULT_BAUD)
    parser.add_argument("--fault", action="append", default=[], help="NAME[:CODE][@N]")
    parser.add_argument("--truth-socket", default=None)
    parser.add_argument("--no-pacing", action="store_true")
    parser.add_argument("--verbose", action="store_true")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO if args.verbose else logging.WARNING)
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
