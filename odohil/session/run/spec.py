"""What a session is to be, as the user gave it: the one input of the lifecycle
(pre-flight, open, connect, run; odohil/session/run/__init__.py)."""

from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

from odohil.science.estimators import EstimateResult
from odohil.session.plans.plan import Plan

Purpose = Literal["calibrate", "validate"]
"""A calibration session, or a validation session (one held-out design, not
estimated: no turn, estimability or trials-per-design check)."""
Mode = Literal["new", "resume", "auto"]
"""Create the session (a folder with a journal is refused), continue an
existing one, or either (``auto``: resume when the folder holds a journal)."""


@dataclass(frozen=True)
class SessionSpec:
    """A session to set up, before anything is checked, written or moved.

    Attributes:
        folder: the session folder.
        mode: see :data:`Mode`.
        robot_path: the robot description file (a new session; a resumed one
            uses its journaled description); ``--robot``.
        robot_toml: the description's text when it comes from elsewhere (the
            demo's, a calibration's journaled one); read from ``robot_path`` if None.
        plan: ``--plan`` (text, or a plan made by the command); None: the
            resumed session's, else ``default_plan``.
        default_plan: the plan of a new session given none (the wizard's).
        measure: ``--measure`` (``fake``, a trial file, ``tcp://HOST:PORT``,
            ``operator``); None: the resumed session's.
        port, baud: ``--port`` and ``--baud`` (None: the journal's, then
            ``[serial]`` of the description, then the backend's default baud).
        truth_socket: the fake robot's truth socket (``--truth-socket``; None:
            the journal's, or the in-process fake's own port).
        seed: the simulated tape's seed (``fake``); None: the journal's, else 0.
        exclude: trial numbers left out of the estimate (``--exclude``).
        purpose: see :data:`Purpose`.
        max_leg_m: the longest leg the floor allows, m (``--max-leg-m``; None: no limit).
        allow_turns: run ``turn`` designs on a robot whose turns carry error.
        allow_few_trials: run designs with fewer trials than the planner's minimum.
        settings: more to journal in the header's settings (the demo's truth,
            a validation's calibration and path).
        note: what a resumed session's ``resumed`` record says (who resumed it).
        calibration: a validation's calibration estimate: every trial is
            predicted under it (the floor-mark choice, the slip check), never
            under an estimate of the held-out trials themselves; None: the
            live estimate, else the description's priors.
    """

    folder: Path
    mode: Mode = "new"
    robot_path: Path | None = None
    robot_toml: str | None = None
    plan: str | Plan | None = None
    default_plan: str | None = None
    measure: str | None = None
    port: str | None = None
    baud: int | None = None
    truth_socket: str | None = None
    seed: int | None = None
    exclude: frozenset[int] = frozenset()
    purpose: Purpose = "calibrate"
    max_leg_m: float | None = None
    allow_turns: bool = False
    allow_few_trials: bool = False
    settings: Mapping[str, Any] = field(default_factory=dict)
    note: Mapping[str, Any] = field(default_factory=dict)
    calibration: EstimateResult | None = None


def default_session_folder() -> Path:
    """``odohil-session-YYYYmmdd-HHMMSS`` in the current directory: the folder
    of a new session given no ``--session``."""
    return Path(f"odohil-session-{time.strftime('%Y%m%d-%H%M%S')}")
