"""The tables ``odohil predict`` and ``odohil covariance`` print for people
(their rows: odohil/session/commands/design.py; a module of its own because the
captions' words load the estimate's, which ``odohil simulate`` does without)."""

from __future__ import annotations

from odohil import units
from odohil.science.closed_forms import ObservableMeans
from odohil.science.covariance import SimulatedMoments
from odohil.science.moments import PoseMoments
from odohil.science.parameters import ErrorParameters
from odohil.science.paths import Design, EncoderPath
from odohil.session.commands.design import covariance_rows, predict_rows
from odohil.session.table_text import TableText
from odohil.session.text.outcome import parameters_line

__all__ = [
    "covariance_table",
    "predict_table",
]


def predict_table(
    design: Design, params: ErrorParameters, means: ObservableMeans, system: units.UnitSystem
) -> TableText:
    """The expected observables of ``design`` under ``params`` (in ``system``'s
    units in the caption)."""
    caption = parameters_line(params.to_si_dict(), system) + f" (1+E_T = {1.0 + params.e_t:g})"
    return TableText(
        f"Expected observables, forth and back {design.label()} (rho = {design.distance_m:g} m)",
        ("observable", "meaning", "value (SI)", "unit", "in degrees"),
        predict_rows(means),
        ("observable", "meaning", "unit"),
        caption,
    )


def covariance_table(
    path: EncoderPath,
    params: ErrorParameters,
    exact: PoseMoments,
    sim: SimulatedMoments | None,
    system: units.UnitSystem,
) -> TableText:
    """The pose change's moments after ``path``: closed form, and simulated
    (with the Monte Carlo standard error) when ``sim``."""
    columns = ["quantity", "closed form"]
    if sim is not None:
        columns.append(f"simulated ({units.plural(sim.n_trials, 'trial')}) +- MC se")
    return TableText(
        f"Pose change after {path.name} ({path.distance_m:g} m driven)",
        columns,
        covariance_rows(exact, sim),
        ("quantity",),
        parameters_line(params.to_si_dict(), system),
    )
