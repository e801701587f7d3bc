"""What odohil says of a session run: where a resumed one stands; what an
unattended run shows while it runs (:class:`RunWatch` on a :class:`RunView`,
the CLI's progress bar); and when one did not finish
(odohil/session/run/running.py's :class:`RunOutcome`) what ended it,
whether the robot reported its stop, whether the journal holds the end, and
the command that continues. Each line of the latter is a :class:`Said`: its
head carries the tone the CLI renders (a colour there), its text follows plain."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal, Protocol

from odohil import units
from odohil.science.estimators import EstimateResult
from odohil.session.journal.events import Solved, Void
from odohil.session.journal.file import Record
from odohil.session.journal.state import SessionState
from odohil.session.measure.tape.records import MeasurementsRejected, Remeasured
from odohil.session.run import RunOutcome
from odohil.session.run.start_pose import StartPose
from odohil.session.text.operator import measured_again, remeasured
from odohil.session.text.outcome import live_e_r

__all__ = [
    "MAY_STILL_MOVE",
    "RunWatch",
    "Said",
    "Tone",
    "error_said",
    "resuming",
    "run_ended",
]

MAY_STILL_MOVE = "the robot may still be moving: use its emergency stop"
"""What odohil says, prominently, when it could not confirm the robot's stop."""

Tone = Literal["plain", "note", "error", "alarm", "title", "good", "done"]
"""How loud a line is: plain, a note (an interrupt), an error, an alarm (the
robot may still be moving, the journal could not be written); the wizard's
also a title (a trial's header, a question that stops the operator), good
news (a solved trial) and done (the session complete)."""


@dataclass(frozen=True)
class Said:
    """One line for the operator: ``head`` said in ``tone``, then ``text``."""

    tone: Tone
    head: str
    text: str = ""


def resuming(folder: Path, state: SessionState) -> str:
    """``resuming FOLDER: 3 of 60 trials done, trial 4 open``."""
    assert state.plan is not None
    done = f"{len(state.completed)} of {units.plural(state.plan.n_trials, 'trial')} done"
    opened = "" if state.open_trial is None else f", trial {state.open_trial.trial} open"
    return f"resuming {folder}: {done}{opened}"


class RunView(Protocol):
    """A run's progress as a user interface shows it (the CLI's progress bar)."""

    def advance(self, completed: int) -> None:
        """``completed`` trials of the plan are done."""
        ...

    def describe(self, text: str) -> None:
        """Show ``text`` beside the progress (the live E_R)."""
        ...

    def status(self, text: str) -> None:
        """A line on the run itself: a voided attempt, where the robot stands."""
        ...

    def say(self, *said: Said) -> None:
        """Lines on what the measurer did."""
        ...


@dataclass
class RunWatch:
    """What ``run``, ``resume``, ``demo`` and ``validate`` show of a session as
    it runs, on ``view``: the progress at each solved trial, a voided attempt,
    distances ``measurer`` took again after a rejection, the live E_R in
    ``system``'s units; at the start check where the robot stands; at the end
    the slip check's summary (:meth:`summary`)."""

    view: RunView
    system: units.UnitSystem = units.DEFAULT_UNIT_SYSTEM
    measurer: str = "the simulated operator"
    remeasured: dict[int, None] = field(default_factory=dict)
    """The trials in which the slip check had a distance taken again, in order."""

    def show_start(self, start: StartPose) -> None:
        """The start check: where the encoders read (with the heading)."""
        self.view.status(f"robot: {start.describe()}")

    def record(self, record: Record, state: SessionState) -> None:
        """Advance on each solved trial; tell voids and rejections."""
        event = record.event
        if isinstance(event, Solved):
            self.view.advance(len(state.completed))
        elif isinstance(event, Void):
            self.view.status(f"trial {event.trial} attempt {event.attempt} void: {event.reason}")
        elif isinstance(event, MeasurementsRejected):
            self.view.say(Said("plain", measured_again(event.trial, self.measurer)))
        elif isinstance(event, Remeasured) and not event.kept:
            self.remeasured.setdefault(event.trial, None)

    def estimated(self, result: EstimateResult, state: SessionState) -> None:
        """Show the live E_R beside the progress."""
        if (text := live_e_r(result, self.system)) is not None:
            self.view.describe(text)

    def summary(self) -> list[Said]:
        """The slip check's work: in which trials a doubted distance was taken again."""
        if not self.remeasured:
            return []
        return [Said("plain", remeasured(list(self.remeasured), self.measurer))]


def error_said(message: str) -> Said:
    """``error: <message>``."""
    return Said("error", "error", f": {message}")


def run_ended(
    outcome: RunOutcome, continue_with: str | None = None, interrupted: str = "interrupted"
) -> list[Said]:
    """How a run that did not finish ended: what ended it (``interrupted``: the
    word for a signal), then what was checked on the way out: the robot's stop
    ("robot stopped" only when the robot reported it), the journal
    ("journaled" only when the closing record is on disk) and the command that
    continues the session (``continue_with``; default ``odohil resume FOLDER``)."""
    said: list[Said] = []
    if outcome.status == "stop unconfirmed":
        said.append(Said("alarm", f"WARNING: {MAY_STILL_MOVE}"))
        if outcome.cause:
            said.append(Said("plain", f"the run ended on: {outcome.cause}"))
        if outcome.stop is None:
            return [*said, Said("plain", f"st sent but not confirmed: {outcome.message}")]
    elif outcome.status == "interrupted":
        said.append(Said("note", interrupted, f" ({outcome.message})"))
    else:
        said.append(error_said(outcome.message))
    stop, folder = outcome.stop, outcome.folder
    again = continue_with or f"odohil resume {folder}"
    if stop is None:
        return said
    if stop.robot_stopped:
        said.append(Said("plain", f"robot stopped (it reports {stop.detail})"))
    else:
        said.append(Said("alarm", MAY_STILL_MOVE, f": {stop.detail}"))
    if stop.journaled:
        said.append(Said("plain", f"session journaled in {folder}; continue with `{again}`"))
    else:
        said.append(
            Said(
                "alarm",
                "the journal could not be written",
                f": {stop.journal_error}; the records before this failure are kept in "
                f"{folder}; free the disk, then `{again}`",
            )
        )
    return said
