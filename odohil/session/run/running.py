"""Run an open session to its outcome: the engine with the caller's observer,
every way it can end caught and told apart (:class:`RunOutcome`), and the
estimate of the trials done by the one recipe (odohil/session/results/outcome.py).
What the outcome means for the exit status is odohil/cli/exit_codes.py's."""

from __future__ import annotations

import contextlib
import functools
import signal
from collections.abc import Callable, Collection
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Literal

from odohil.errors import MeasurementError, OdohilError, StopUnconfirmedError
from odohil.science.estimators import EstimateResult
from odohil.science.estimators.paths import estimate_paths
from odohil.science.pose_selection import ParameterBelief
from odohil.session.journal.state import (
    CompletedTrial,
    SessionState,
    description_of_header,
    load_session,
    session_path_trials,
)
from odohil.session.measure.protocol import PoseSource
from odohil.session.results.outcome import EstimateOutcome, estimate_state
from odohil.session.robots.protocol import SampleCallback
from odohil.session.run.engine import (
    IncrementalLiveEstimator,
    LiveEstimator,
    MotionSettings,
    SessionEngine,
    SessionObserver,
    StartCheck,
    StopOutcome,
)
from odohil.session.run.opening import Opened
from odohil.session.signals import signal_name, signal_of

RunStatus = Literal["finished", "interrupted", "error", "stop unconfirmed"]


@dataclass(frozen=True)
class RunOutcome:
    """How a session run ended.

    Attributes:
        status: finished, interrupted (a signal), error, or stop unconfirmed
            (the robot may still be moving).
        folder: the session folder.
        state: the session as journaled at the end (read back from disk when
            the run did not finish: a signal may land between a record and
            the state it makes).
        estimated: computes :attr:`estimate` (at its first reading, once).
        stop: what the engine checked on the way out (None when it finished).
        message: what ended it ("Ctrl-C", "SIGTERM received", the error).
        cause: for a stop unconfirmed, what the run had ended on.
        signal: the signal number of an interrupted run.
    """

    status: RunStatus
    folder: Path
    state: SessionState
    estimated: Callable[[], EstimateOutcome] = field(repr=False, compare=False)
    stop: StopOutcome | None = None
    message: str = ""
    cause: str = ""
    signal: int | None = None

    @functools.cached_property
    def estimate(self) -> EstimateOutcome:
        """The final estimate and verdict (finished) or the partial one of the
        trials done, by the one recipe: computed when first read, since a
        caller may have no use for it (a validation session's own trials:
        ``odohil validate`` tests them against the calibration, and their
        estimate with profile intervals cost seconds per validation of
        general paths), and the same value whenever it is read (a pure
        function of :attr:`state`)."""
        return self.estimated()

    def to_json_dict(self, exit_code: int) -> dict[str, Any]:
        """The ``--json`` object of a session command: the status with the
        final estimate (SI) when it finished with one, as ``estimate --json``
        gives it (the flagged and ambiguous trials named), else with the exit
        status and :meth:`details`."""
        if self.status == "finished" and self.estimate.result is not None:
            return {"status": self.status, **self.estimate.to_json_dict()}
        return {"status": self.status, "exit_code": exit_code, **self.details()}

    def details(self) -> dict[str, Any]:
        """For ``--json``: a finished run without an estimate, its verdict;
        a run that did not finish, how it ended and its partial estimate."""
        if self.status == "finished":
            if self.estimate.result is not None:
                return {}
            return {"verdict": {"status": self.estimate.status, "reasons": [self.estimate.problem]}}
        stop = self.stop
        info: dict[str, Any] = {
            **({} if self.signal is None else {"signal": signal_name(self.signal)}),
            "message": self.message,
            "stop_confirmed": None if stop is None else stop.robot_stopped,
            "journaled": None if stop is None else stop.journaled,
            "trials_done": len(self.state.completed),
            "session": str(self.folder),
        }
        partial = self.estimate.result
        if partial is None:
            info["partial_estimate_note"] = self.estimate.problem
        info["partial_estimate"] = None if partial is None else partial.to_json_dict()
        return info


def interrupt_text(exc: BaseException) -> str:
    """What ended the run, in words: "Ctrl-C" or "SIGTERM received" (never
    an exception's class name)."""
    signum = signal_of(exc)
    if signum == signal.SIGINT:
        return "Ctrl-C"
    return str(exc) or f"{signal_name(signum)} received"


def interrupted_before_run(exc: BaseException) -> dict[str, Any]:
    """For ``--json``: a signal ended the command before the session ran."""
    return {
        "status": "interrupted",
        "signal": signal_name(signal_of(exc)),
        "message": interrupt_text(exc) + " before the session ran: nothing moved",
        "stop_confirmed": None,
        "partial_estimate": None,
    }


def refused_before_run(message: str, exit_code: int) -> dict[str, Any]:
    """For ``--json``: the command refused its input (exit 2: a bad option
    value, an unreadable file, a failed pre-flight check; or a pre-flight
    check of the error class, exit 1) before doing anything."""
    return {"status": "refused", "exit_code": exit_code, "error": message}


def final_estimate(state: SessionState, exclude: Collection[int] = ()) -> EstimateOutcome:
    """A session's estimate and verdict by the one recipe
    (odohil/session/results/outcome.py): every solved trial but the ambiguous ones and
    those in ``exclude`` (numbers of trials not yet done are ignored)."""
    done = {t.trial for t in state.completed}
    return estimate_state(state, [t for t in exclude if t in done])


class RecipeLiveEstimator:
    """The live estimate by the one recipe (:func:`final_estimate` of the
    session so far), so that the interval an operator sees after each trial is
    the one ``odohil estimate`` gives on the same trials. A robust fit per
    trial: a second or so on tens of trials."""

    def __init__(self, state_of: Callable[[], SessionState], exclude: Collection[int]) -> None:
        self.state_of = state_of
        self.exclude = exclude
        self._done = -1
        self._result: EstimateResult | None = None

    def add(self, trial: CompletedTrial) -> EstimateResult | None:
        """The estimate of every trial completed so far (``trial`` among them)."""
        state = self.state_of()
        if len(state.completed) != self._done:  # a resumed run catches up trial by trial
            self._done = len(state.completed)
            self._result = final_estimate(state, self.exclude).result
        return self._result


class PathBeliefEstimator:
    """The live belief of a session with general paths behind a progress bar:
    the recipe's fit of every trial so far (as :func:`final_estimate`: the
    same trials, exclusions, turn model and robust fit, so the same values,
    standard errors and correlations, which are all that the engine's belief
    and the bar read) with Wald intervals instead of the recipe's profile
    intervals, which no reader of a live estimate needs and which cost about
    half of each fit (``estimate_paths(intervals="wald")``). The journal's
    ``estimate`` records carry these intervals; the final estimate, and the
    wizard's live one (:class:`RecipeLiveEstimator`), are the recipe's.

    Args:
        start: the session as opened (its header, and the trials a resumed
            run catches up on: fitted once, at the last of them).
        exclude: trial numbers left out (those not yet done are ignored).
    """

    def __init__(self, start: SessionState, exclude: Collection[int]) -> None:
        self.start = start
        self.exclude = exclude
        self._catch_up = sum(1 for t in start.completed if not t.ambiguous)
        self._trials: list[CompletedTrial] = []
        self._turns_exact: bool | None = None

    def add(self, trial: CompletedTrial) -> EstimateResult | None:
        """The belief after every trial added so far (``trial`` the last)."""
        self._trials.append(trial)
        if len(self._trials) < self._catch_up:
            return None  # a resumed run catching up: only its last trial is fitted
        state = replace(self.start, completed=tuple(self._trials))
        if self._turns_exact is None:  # the journaled description does not change
            self._turns_exact = description_of_header(state).robot.turns_exact
        done = {t.trial for t in self._trials}
        left_out = tuple(sorted(t for t in self.exclude if t in done))
        try:
            return estimate_paths(
                session_path_trials(state),
                turns_exact=self._turns_exact,
                exclude=left_out,
                intervals="wald",
            )
        except MeasurementError:  # too few trials yet: the recipe's outcome has none either
            return None


def progress_estimator(opened: Opened) -> LiveEstimator:
    """The live estimator behind a progress bar: the cheap incremental fit for
    a plan of forth-and-back designs; for a plan with general paths, which the
    incremental fit cannot fold in, the recipe's fit of every trial
    (:class:`PathBeliefEstimator`): a live belief without the squares' turn
    errors mis-predicts every square, so the slip check trips on clean tape
    readings and the prior pulls the choice of pose (issue 19,
    tests/session/test_path_belief.py)."""
    exclude = opened.prepared.spec.exclude
    if opened.prepared.plan.has_paths:
        return PathBeliefEstimator(opened.state, exclude)
    return IncrementalLiveEstimator(exclude)


def validation_calibration(
    given: EstimateResult | None, state: SessionState
) -> EstimateResult | None:
    """The calibration a validation session's trials are measured under:
    ``given`` (the spec's), else the estimate of the calibration session its
    header names (``validation_of``: a resumed validation, `odohil resume`),
    else None (a calibration session, or a calibration that gives no estimate
    any more: the trials are then measured under the live estimate or the
    priors)."""
    if given is not None:
        return given
    folder = state.header.settings.get("validation_of")
    if not folder:
        return None
    try:
        return estimate_state(load_session(Path(str(folder))).state).result
    except (OdohilError, OSError):
        return None


def run_session(
    opened: Opened,
    observer: SessionObserver | None = None,
    *,
    source: PoseSource | None = None,
    estimator: LiveEstimator | None = None,
    motion: MotionSettings | None = None,
    start_check: StartCheck | None = None,
    on_sample: SampleCallback | None = None,
) -> RunOutcome:
    """Run the engine on ``opened`` (with ``source``, else the session's own;
    the live estimate by ``estimator``, else by the one recipe:
    :class:`RecipeLiveEstimator`; none for a validation, whose belief is its
    calibration) to its :class:`RunOutcome`. The engine journals
    ``stopped`` and stops the robot before an error gets here; a
    KeyboardInterrupt (any signal of odohil/session/signals.py) ends the
    run as ``interrupted``."""
    exclude = opened.prepared.spec.exclude
    chosen = source or opened.source
    assert chosen is not None, "the operator's source is the caller's to give"
    calibration = validation_calibration(opened.prepared.spec.calibration, opened.state)
    belief = None if calibration is None else (
        ParameterBelief.from_result(
            calibration, opened.prepared.description.priors,
            turns_exact=opened.prepared.description.robot.turns_exact,
        )
    )  # fmt: skip
    engine = SessionEngine(
        opened.journal,
        opened.state,
        opened.robot,
        chosen,
        # a validation's trials are measured under the calibration and tested
        # against it: an estimate of its own trials so far is neither its
        # belief nor its result, and it cost a fit per trial (every square of
        # a validation of general paths: tests/create2/test_validate_turn_free.py)
        estimator=None
        if calibration is not None
        else (estimator or RecipeLiveEstimator(lambda: engine.state, exclude)),
        observer=observer,
        motion=motion,
        connection=opened.prepared.settings,
        on_sample=on_sample,
        start_check=start_check,
        belief=belief,
    )
    try:
        state = engine.run()
    except StopUnconfirmedError as exc:
        cause = exc.__cause__
        why = "" if cause is None else (
            interrupt_text(cause) if isinstance(cause, KeyboardInterrupt)
            else str(cause) or "an error without a message"
        )  # fmt: skip
        return _ended("stop unconfirmed", engine, exclude, str(exc), cause=why)
    except KeyboardInterrupt as exc:
        signum = signal_of(exc)
        return _ended("interrupted", engine, exclude, interrupt_text(exc), signal=signum)
    except OdohilError as exc:
        return _ended("error", engine, exclude, str(exc))
    finished = functools.partial(final_estimate, state, exclude)
    return RunOutcome("finished", opened.journal.folder, state, finished)


def _ended(
    status: RunStatus,
    engine: SessionEngine,
    exclude: Collection[int],
    message: str,
    cause: str = "",
    signal: int | None = None,
) -> RunOutcome:
    state = engine.state
    with contextlib.suppress(OdohilError):
        state = load_session(engine.journal.folder).state
    estimated = functools.partial(final_estimate, state, exclude)
    folder = engine.journal.folder
    return RunOutcome(status, folder, state, estimated, engine.stop_outcome, message, cause, signal)
