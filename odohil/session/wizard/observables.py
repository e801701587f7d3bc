"""phi1..phi5 of each design of a session's completed trials, as the wizard
shows them after every trial (the rows of its table: :func:`observables_rows`)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from odohil import units
from odohil.science.grouping import by_design
from odohil.science.observables import Observables, observables
from odohil.session.journal.state import CompletedTrial
from odohil.session.table_text import TableText

__all__ = [
    "observables_table",
]


def observables_by_design(
    trials: Sequence[CompletedTrial],
) -> list[tuple[str, int, Observables | None]]:
    """Per design (label, trials, observables): the observables of the
    design's trials, their headings taken near their circular mean; None for
    a design with fewer than two trials."""
    rows: list[tuple[str, int, Observables | None]] = []
    for design, members in by_design(trials).items():
        if len(members) < 2:
            rows.append((design.label(), len(members), None))
            continue
        poses = np.array([t.pose_change for t in members], dtype=np.float64)
        poses[:, 2] = units.angle_near(poses[:, 2], units.circular_mean(poses[:, 2]))
        rows.append((design.label(), len(members), observables(poses)))
    return rows


OBSERVABLE_COLUMNS = ("design", "n", "phi1 deg", "phi2 deg^2", "phi3 mm", "phi4 mm", "phi5 mm^2")
"""The columns of :func:`observables_rows`."""


def observables_table(trials: Sequence[CompletedTrial]) -> TableText:
    """The wizard's table of observables per design (:func:`observables_rows`)."""
    rows = observables_rows(trials)
    title = "Observables per design"
    return TableText(title, OBSERVABLE_COLUMNS, rows, ("design",), title_left=True)


def observables_rows(trials: Sequence[CompletedTrial]) -> list[tuple[str, ...]]:
    """The rows of the table of observables per design (:data:`OBSERVABLE_COLUMNS`:
    phi1 deg, phi2 deg^2, phi3 and phi4 mm, phi5 mm^2); a design with fewer
    than two trials ``needs 2 trials``."""
    rows: list[tuple[str, ...]] = []
    for label, n, phi in observables_by_design(trials):
        if phi is None:
            rows.append((label, str(n), "needs 2 trials", "", "", "", ""))
            continue
        rows.append(
            (
                label,
                str(phi.n_trials),
                f"{units.radians_to_degrees(phi.phi1):.4g}",
                f"{units.rad2_to_deg2(phi.phi2):.3g}",
                f"{1e3 * phi.phi3:.3g}",
                f"{1e3 * phi.phi4:.3g}",
                f"{1e6 * phi.phi5:.3g}",
            )
        )
    return rows
