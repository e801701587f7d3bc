"""The wizard's live screen (issue 18): the estimate shown after a trial is
the one recipe's (odohil/session/results/outcome.py), so the live interval for E_R
after the last trial is the one ``odohil estimate`` gives on the same trials.
In process: the session engine on the in-process fake robot, the wizard's
watch (odohil/session/wizard/dialogue.py) on its screen writing to a string."""

from __future__ import annotations

import io
from pathlib import Path

from rich.console import Console

from odohil.cli.render import drawn
from odohil.cli.wizard import WizardScreen
from odohil.session.measure.tape.distances import FakeTruthSource
from odohil.session.measure.tape.source import TapeSource
from odohil.session.plans.plan import parse_plan
from odohil.session.run import final_estimate
from odohil.session.run.engine import IncrementalLiveEstimator, SessionEngine, start_session
from odohil.session.text.outcome import parameters_text
from odohil.session.wizard.dialogue import OperatorWatch
from odohil.session.wizard.interrupts import Interrupts
from tests.session.helpers import FAST, ROBOT_TOML, description, fake_robot


def _text(renderable: object) -> str:
    out = io.StringIO()
    Console(file=out, width=200, color_system=None).print(renderable)
    return out.getvalue()


def test_live_estimate_after_the_last_trial_is_the_final_recipes(tmp_path: Path) -> None:
    out = io.StringIO()
    console = Console(file=out, width=200, color_system=None)
    with fake_robot(f"seed=5&{FAST}") as (robot, truth):
        journal, state = start_session(
            tmp_path / "s", ROBOT_TOML, parse_plan("k=1,l=1,n=3"), measure="fake", settings={}
        )
        interrupts = Interrupts(print, 130, 4, "the robot may still be moving")
        observer = OperatorWatch(WizardScreen(console), interrupts)
        with journal:
            final = SessionEngine(
                journal,
                state,
                robot,
                TapeSource(FakeTruthSource(truth, description(), seed=3), description()),
                estimator=IncrementalLiveEstimator(),
                observer=observer,
            ).run()
    outcome = final_estimate(final)
    assert outcome.result is not None
    shown = out.getvalue()
    last = shown.rsplit("Trial 3 solved", 1)[1]
    assert _text(drawn(parameters_text(outcome.result))) in last
