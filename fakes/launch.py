"""Start a fake robot and announce it, and the options every fake takes.

Whoever starts a fake (``odohil emulate``, ``python -m fakes.nomad``,
``python -m fakes.create2``, fakes/*/process.py) reads two lines from it: the
pty device path, then the truth socket path.
"""

from __future__ import annotations

import argparse
import logging
import shutil
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TextIO

from odohil.errors import ParameterError
from odohil.science.parameters import ErrorParameters

OnReady = Callable[[str, str], None]
"""Called once with (pty device path, truth socket path) when the fake is open."""


@dataclass(frozen=True)
class EmulateOptions:
    """What ``odohil emulate`` hands a fake's ``emulate`` hook (the function a
    backend names in its ``FakeFacts.emulator``; e.g. fakes/nomad/run.py).

    Attributes:
        seed: seed of the odometry noise (None: fresh).
        paper: the true E_R deg/m, E_T, K_theta deg^2/m, K_rho m.
        time_scale: simulated seconds per wall second.
        baud: line rate, bit/s (pacing and the pty speed).
        pacing: carry bytes at the line rate.
        faults: fault strings as the fake parses them.
        truth_socket: the truth socket's path (None: a temporary one).
    """

    seed: int | None
    paper: tuple[float, float, float, float]
    time_scale: float
    baud: int
    pacing: bool
    faults: tuple[str, ...]
    truth_socket: str | None


def run_announced(
    serve: Callable[[Path, OnReady], None],
    *,
    truth_socket: str | None,
    tmp_prefix: str,
    out: TextIO,
) -> None:
    """Run ``serve(truth_path, on_ready)``, printing the two lines on ``out``.

    ``on_ready`` writes the pty device path as the first line of ``out`` and
    the truth socket path as the second, then flushes. Without
    ``truth_socket`` the socket goes into a fresh temporary directory (named
    with ``tmp_prefix``), removed at exit.
    """
    tmpdir: str | None = None
    if truth_socket is None:
        tmpdir = tempfile.mkdtemp(prefix=tmp_prefix)
        path = Path(tmpdir) / "truth.sock"
    else:
        path = Path(truth_socket)

    def ready(device: str, socket_path: str) -> None:
        out.write(f"{device}\n{socket_path}\n")
        out.flush()

    try:
        serve(path, ready)
    finally:
        if tmpdir is not None:
            shutil.rmtree(tmpdir, ignore_errors=True)


def add_truth_options(parser: argparse.ArgumentParser, truth: ErrorParameters) -> None:
    """``--seed`` and the fake's true error parameters, in the paper's units.

    The same names and units in every fake: ``--E-R`` deg/m, ``--E-T`` (no
    unit), ``--K-theta`` deg^2/m, ``--K-rho`` m, each defaulting to ``truth``.
    """
    paper = truth.to_paper_units()
    parser.add_argument("--seed", type=int, default=None)
    parser.add_argument("--E-R", dest="e_r", type=float, default=paper["E_R"], help="deg/m")
    parser.add_argument("--E-T", dest="e_t", type=float, default=paper["E_T"], help="no unit")
    parser.add_argument(
        "--K-theta", dest="k_theta", type=float, default=paper["K_theta"], help="deg^2/m"
    )
    parser.add_argument("--K-rho", dest="k_rho", type=float, default=paper["K_rho"], help="m")


def add_serving_options(parser: argparse.ArgumentParser) -> None:
    """``--truth-socket PATH``, ``--no-pacing`` and ``--verbose``, in every fake."""
    parser.add_argument("--truth-socket", default=None)
    parser.add_argument("--no-pacing", action="store_true")
    parser.add_argument("--verbose", action="store_true")


def parse_and_log(parser: argparse.ArgumentParser, argv: list[str] | None) -> argparse.Namespace:
    """Parse ``argv``; log INFO with ``--verbose``, else WARNING."""
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO if args.verbose else logging.WARNING)
    return args


def checked_by(parse: Callable[[str], object]) -> Callable[[str], str]:
    """An argparse ``type`` that refuses a value ``parse`` refuses
    (:class:`~odohil.errors.ParameterError`, e.g. an unknown fault) as a bad
    option is refused (usage, the option and the message, exit 2; no
    traceback), and passes the text on unchanged."""

    def check(text: str) -> str:
        try:
            parse(text)
        except ParameterError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None
        return text

    return check
