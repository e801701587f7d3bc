"""What the design tools (``odohil predict``, ``covariance``, ``simulate``)
compute beyond calling science: the path their options name, their JSON
documents (SI), the rows of their tables, and the simulated trials written as
a trial file."""

from __future__ import annotations

import math
import os
import tempfile
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from odohil import units
from odohil.errors import ParameterError
from odohil.science.closed_forms import ObservableMeans, forth_and_back_means
from odohil.science.covariance import SimulatedMoments, predicted_moments, simulated_moments
from odohil.science.limits import check_simulation_work, segments_of
from odohil.science.moments import PoseMoments
from odohil.science.parameters import SI_UNITS, ErrorParameters
from odohil.science.paths import (
    Design,
    EncoderPath,
    FloatArray,
    Variant,
    floor_choreography,
    square,
)
from odohil.science.simulator import simulate

__all__ = [
    "as_driven",
    "check_simulation",
    "covariance_document",
    "fresh_seed",
    "named_path",
    "path_moments",
    "predict_document",
    "simulate_as_driven",
    "write_simulated_trials",
]

COMPONENTS = ("x", "y", "Delta")
COMPONENT_UNITS = ("m", "m", "rad")
OBSERVABLES = {  # name: (SI unit, meaning)
    "phi1": ("rad", "mean heading change"),
    "phi2": ("rad^2", "variance of the heading change"),
    "phi3": ("m", "mean x of the end point"),
    "phi4": ("m", "mean y of the end point"),
    "phi5": ("m^2", "mean squared distance start-end"),
    "x": ("m", "<x>"),
    "y": ("m", "<y>"),
}
TRIAL_FILE_HEADER = "k,l_m,variant,dx_m,dy_m,dtheta_rad"


def named_path(
    kind: str | None, k: float | None, l_m: float | None, variant: Variant, side: float | None
) -> EncoderPath:
    """The path of ``--path`` (``forth-and-back`` or ``square``; None: the one
    ``--k``/``--l`` or ``--side`` names).

    Raises:
        ParameterError: options of both paths, or of neither, or missing ones.
    """
    if kind is None:
        if side is not None and k is None and l_m is None:
            kind = "square"
        elif side is None and (k is not None or l_m is not None):
            kind = "forth-and-back"
        else:
            raise ParameterError(
                "give --k K --l L (forth-and-back) or --side S (square)"
                + (", not both" if side is not None else "")
            )
    if kind == "forth-and-back":
        if k is None or l_m is None:
            raise ParameterError("--path forth-and-back needs --k and --l")
        if side is not None:
            raise ParameterError("--side is for --path square")
        return Design(k, l_m, variant).path()
    if side is None:
        raise ParameterError("--path square needs --side")
    if k is not None or l_m is not None:
        raise ParameterError("--k and --l are for --path forth-and-back")
    return square(side)


def path_moments(
    path: EncoderPath,
    params: ErrorParameters,
    n_simulate: int | None,
    seed: int | None,
    segment_m: float,
) -> tuple[PoseMoments, SimulatedMoments | None]:
    """The closed-form moments of the path's pose change, and simulated ones
    when ``n_simulate`` is given.

    Raises:
        ParameterError: more simulation work than one command runs.
    """
    if n_simulate is None:
        return predicted_moments(path, params), None
    check_simulation_work(n_simulate, segments_of(path.legs.length_m.tolist(), segment_m))
    sim = simulated_moments(path, params, n_simulate, seed=seed, segment_m=segment_m)
    return predicted_moments(path, params), sim


def _matrix(matrix: FloatArray) -> list[list[float]]:
    return [[float(v) for v in row] for row in matrix]


def covariance_rows(exact: PoseMoments, sim: SimulatedMoments | None) -> list[tuple[str, ...]]:
    """The rows of ``odohil covariance``'s table for people: (quantity and its
    unit, closed form, and when simulated the simulated value +- its Monte
    Carlo standard error) for the means, the covariance entries and the
    standard deviations (mm, deg)."""
    rows: list[tuple[str, ...]] = []
    for i, (name, unit) in enumerate(zip(COMPONENTS, COMPONENT_UNITS, strict=True)):
        simulated = "" if sim is None else f"{sim.mean[i]:.6g} +- {sim.mean_se[i]:.2g}"
        rows.append((f"mean {name} ({unit})", f"{exact.mean[i]:.6g}", simulated))
    for i in range(3):
        for j in range(i, 3):
            unit = units.product_unit(COMPONENT_UNITS[i], COMPONENT_UNITS[j])
            simulated = "" if sim is None else f"{sim.cov[i, j]:.6g} +- {sim.cov_se[i, j]:.2g}"
            quantity = f"cov({COMPONENTS[i]}, {COMPONENTS[j]}) ({unit})"
            rows.append((quantity, f"{exact.cov[i, j]:.6g}", simulated))
    sd = [math.sqrt(max(exact.cov[i, i], 0.0)) for i in range(3)]
    sds = f"{sd[0] * 1e3:.4g}, {sd[1] * 1e3:.4g}; {math.degrees(sd[2]):.4g}"
    rows.append(("sd x, y (mm); sd Delta (deg)", sds, ""))
    return rows if sim is not None else [row[:2] for row in rows]


def predict_rows(means: ObservableMeans) -> list[tuple[str, str, str, str, str]]:
    """The rows of ``odohil predict``'s table for people: observable, meaning,
    value (SI), unit, and phi1 and phi2 in degrees."""
    degrees = {
        "phi1": f"{units.radians_to_degrees(means.phi1):.6g} deg",
        "phi2": f"{units.rad2_to_deg2(means.phi2):.6g} deg^2",
    }
    rows = []
    for key, value in means.as_dict().items():
        unit, meaning = OBSERVABLES[key]
        rows.append((key, meaning, f"{value:.6g}", unit, degrees.get(key, "")))
    return rows


def covariance_document(
    path: EncoderPath, params: ErrorParameters, exact: PoseMoments, sim: SimulatedMoments | None
) -> dict[str, object]:
    """The JSON document of ``odohil covariance --json``."""
    document: dict[str, object] = {
        "path": path.name,
        "distance_m": path.distance_m,
        "parameters_si": params.to_si_dict(),
        "components": list(COMPONENTS),
        "units": {"mean": list(COMPONENT_UNITS), "cov": "products of the component units"},
        "closed_form": {"mean": [float(v) for v in exact.mean], "cov": _matrix(exact.cov)},
    }
    if sim is not None:
        document["simulated"] = {
            "n_trials": sim.n_trials,
            "mean": [float(v) for v in sim.mean],
            "mean_se": [float(v) for v in sim.mean_se],
            "cov": _matrix(sim.cov),
            "cov_se": _matrix(sim.cov_se),
        }
    return document


def predict_document(
    design: Design, params: ErrorParameters, means: ObservableMeans | None = None
) -> dict[str, Any]:
    """The JSON document of ``odohil predict --json``: phi1..phi5, <x>, <y> (SI)."""
    means = means or forth_and_back_means(design, params)
    document: dict[str, Any] = dict(means.as_dict())
    document["design"] = {"k": design.k, "l_m": design.l_m, "variant": design.variant}
    document["parameters"] = params.to_si_dict()
    document["units"] = {
        **{name: unit for name, (unit, _) in OBSERVABLES.items()},
        "parameters": dict(SI_UNITS),
        "design": {"k": "1", "l_m": "m"},
    }
    return document


def fresh_seed() -> int:
    """A fresh random seed (63 bits) for a simulation given none, to report."""
    return int(np.random.SeedSequence().generate_state(1, dtype=np.uint64)[0] >> 1)


def check_simulation(design: Design, trials: int, segment_m: float, out: Path) -> None:
    """Refuse a simulation before it runs: too much work, or an ``--out`` that
    cannot be written.

    Raises:
        ParameterError: naming ``--trials`` or ``--out``.
    """
    try:
        check_simulation_work(trials, segments_of(design.path().legs.length_m.tolist(), segment_m))
    except ParameterError as exc:
        raise ParameterError(f"--trials: {exc}") from None
    if not out.parent.is_dir():
        raise ParameterError(f"--out: folder {str(out.parent)!r} does not exist")
    if out.is_dir():
        raise ParameterError(f"--out: {str(out)!r} is a folder")


def write_simulated_trials(
    out: Path, design: Design | Sequence[Design], pose_change: FloatArray
) -> None:
    """Write the trial file (a header, then one row per trial, floats in full
    precision: k, l_m m, variant, dx_m, dy_m m in the start frame,
    dtheta_rad) through a temporary file next to ``out`` and a rename: never
    a half-written ``out``. ``design``: every row's, or each row's in turn (a
    backward one's variant written with ``-backward``, as the reader takes it).

    Raises:
        OSError: it cannot be written.
    """
    rows = [design] * len(pose_change) if isinstance(design, Design) else list(design)
    handle, temporary = tempfile.mkstemp(prefix=f".{out.name}.", suffix=".tmp", dir=out.parent)
    try:
        with os.fdopen(handle, "w", encoding="utf-8", newline="") as stream:
            stream.write(TRIAL_FILE_HEADER + "\n")
            for row, (dx, dy, dtheta) in zip(rows, pose_change.tolist(), strict=True):
                prefix = f"{float(row.k)!r},{float(row.l_m)!r},{row.variant_text},"
                stream.write(f"{prefix}{dx!r},{dy!r},{dtheta!r}\n")
        os.replace(temporary, out)
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise


def as_driven(design: Design, trials: int) -> tuple[Design, ...]:
    """Each of ``trials`` trials of ``design`` as a plan of it drives them
    (odohil/science/paths.py ``floor_choreography``): a one-way design's
    trials go out and back, every other one backwards; a two-way design's all
    forwards."""
    driven = floor_choreography([(design, trials)])
    return tuple(driven.trial(number)[0] for number in range(1, trials + 1))


def simulate_as_driven(
    designs: Sequence[Design],
    params: ErrorParameters,
    seed: int,
    segment_m: float,
    progress: Callable[[int], None] | None = None,
) -> FloatArray:
    """The real pose change (n x 3: dx m, dy m, dtheta rad) of each trial of
    ``designs`` in turn, one simulation a direction: the forward trials with
    ``seed`` (so an all-forward list gives what one simulation of ``seed``
    gives), the backward ones with the seed sequence (``seed``, 1)."""
    poses = np.empty((len(designs), 3))
    done = 0
    for backward in (False, True):
        rows = [i for i, d in enumerate(designs) if d.backward == backward]
        if not rows:
            continue
        start = done

        def step(count: int, start: int = start) -> None:
            if progress is not None:
                progress(start + count)

        rng = seed if not backward else np.random.default_rng(np.random.SeedSequence([seed, 1]))
        result = simulate(
            designs[rows[0]].path(), params, len(rows), seed=rng, segment_m=segment_m, progress=step
        )
        poses[rows] = result.pose_change
        done += len(rows)
    return poses
