"""The demo's session: a whole calibration against the fake robot of a backend,
in process behind its pyserial URL (``fakerobot://``, ``fakecreate2://``: the
scheme its backend declares, odohil/session/robots/registry.py ``fake_hooks``), with
known, exaggerated error parameters (:data:`DEMO_TRUTH`) and the fake's ground
truth as measurement source (1 mm tape noise)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

from odohil import units
from odohil.errors import ParameterError
from odohil.science.parameters import SI_UNITS, ErrorParameters
from odohil.session.robots.registry import backend_names, robot_facts
from odohil.session.run import SessionSpec
from odohil.session.text.outcome import parameters_line

__all__ = [
    "demo_session",
]

DEMO_TRUTH = ErrorParameters.from_paper_units(-1.0, -0.05, 0.3, 9e-4)
"""The fake robot's true parameters: the paper's robot's (-0.202 deg/m, -0.02,
0.012 deg^2/m, 3.6e-5 m) scaled by about 5, 2.5, 25 and 25, so that the
odometry error of a 4 m trial stands well clear of 1 mm tape noise."""
DEMO_PLAN = "k=1,l=2,n=24;k=0.5,l=2,n=24"
"""Closed 4 m runs (E_R, K_theta, K_rho) and one-way 2 m runs (E_T)."""
TURN_FREE_PLAN = "k=1,l=2,n=12,variant=reverse;k=0.5,l=2,n=12,variant=reverse"
"""For a robot whose turns carry error (docs/create2.md): closed 4 m runs and
one-way 2 m runs, turn-free; fewer trials, as its fake runs on a slower clock."""
DEMO_ROBOT_TOML = """\
[screws]
A = [0.20, 0.0]
B = [-0.10, 0.173]
C = [-0.10, -0.173]
[measurement]
sigma_m = 0.001
cross = [["A", "B"], ["B", "C"]]
"""


@dataclass(frozen=True)
class Demo:
    """The demo's session to run.

    Attributes:
        spec: the session (its plan turn-free on a robot whose turns carry error).
        port: the in-process fake's URL, its true parameters in the query.
        truth: the fake's true parameters, SI, by name.
    """

    spec: SessionSpec
    port: str
    truth: Mapping[str, float]

    def heading(self, system: units.UnitSystem) -> str:
        """``fake robot at URL; its true parameters: E_R = ...`` (in ``system``'s units)."""
        truth = parameters_line(self.truth, system)
        return f"fake robot at {self.port}; its true parameters: {truth}"

    def truth_document(self) -> dict[str, dict[str, dict[str, float | str]]]:
        """For ``odohil demo --json``: ``{"truth": {name: {"value", "unit"}}}`` (SI)."""
        return {"truth": {n: {"value": v, "unit": SI_UNITS[n]} for n, v in self.truth.items()}}


def demo_session(protocol: str, seed: int, folder: Path) -> Demo:
    """The demo of the backend ``protocol`` in ``folder`` (the fake's and the
    tape's seed ``seed``).

    Raises:
        ParameterError: the backend declares no fake robot (the message names
            the backends that do).
    """
    facts = robot_facts(protocol)
    if facts.fake is None:
        demoable = [name for name in backend_names() if robot_facts(name).fake is not None]
        raise ParameterError(
            f"one of {', '.join(demoable)} (a backend with a fake robot); got {protocol!r}"
        )
    options = {"time_scale": facts.fake.demo_time_scale, **dict(facts.fake.demo_url_options)}
    paper = DEMO_TRUTH.to_paper_units()
    query = "&".join(
        [f"seed={seed}", *(f"{name}={value!r}" for name, value in options.items())]
        + [f"{name}={paper[name]!r}" for name in ("E_R", "E_T", "K_theta", "K_rho")]
    )
    port = f"{facts.fake.url_scheme}//?{query}"
    truth = DEMO_TRUTH.to_si_dict()
    spec = SessionSpec(
        folder,
        "new",
        robot_toml=DEMO_ROBOT_TOML + f'[robot]\nprotocol = "{protocol}"\n',
        plan=DEMO_PLAN if facts.turns_exact else TURN_FREE_PLAN,
        measure="fake",
        port=port,
        seed=seed,
        settings={"truth": truth},
    )
    return Demo(spec, port, truth)
