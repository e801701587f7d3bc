"""phi1..phi5 of each design of a session's completed trials, as the wizard
shows them after every trial."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from odohil import units
from odohil.science.grouping import by_design
from odohil.science.observables import Observables, observables
from odohil.session.state import CompletedTrial


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
