"""The calibration session engine: the trial loop, journaled step by step.

The engine drives a :class:`~odohil.session.robots.protocol.Robot` (any backend) and
asks a :class:`~odohil.session.measure.protocol.PoseSource` for each trial's real
pose change; it names neither a robot nor a measuring instrument. One trial
attempt:

1. the robot is brought to rest and its odometry re-zeroed (``Robot.zero``);
2. the source's ``at_start`` (the operator marks the floor; the fake's truth
   channel reads the true start pose); journaled as ``trial_start``;
3. ``motion_start`` is journaled, the robot drives the design (``Robot.drive``,
   every odometry sample to ``on_sample``);
4. the source's ``at_end``; the odometry end pose and trajectory are
   journaled as ``motion_done``;
5. the source's ``pose_change``, given the model's predictive distribution of
   the pose at the current estimate (or the description's priors); a source
   that takes several readings journals each through ``log`` as its own
   events (the tape's: odohil/session/measure/tape/records.py), which the state folds
   into the source's own readings and hands back in the next context,
   unopened; the pose is checked
   against the encoders and the prediction (odohil/session/measure/plausibility.py:
   an implausible one is journaled ``void`` with its likely cause and stops
   the session before the next motion) and journaled (``solved``); an
   ambiguous one is left out of every estimate;
6. the live estimate is updated (``estimate``).

Every record is on disk (fsync) before the next step starts, so after a crash
:func:`resume_session` continues exactly where the journal stops: an attempt
cut off before or during its motion is voided and the trial redone; one whose
motion finished resumes where its source's readings stop. On any failure, Ctrl-C
or other signal (:mod:`odohil.session.signals`) the engine stops the robot and
waits, within ``MotionSettings.stop_timeout_s``, for it to report that it
stopped (``Robot.stop_and_confirm``); it journals ``void`` for an attempt cut off before its motion
ended, then ``stopped`` (the robot reported it) or ``stop_unconfirmed`` (it did
not: :class:`~odohil.errors.StopUnconfirmedError` is raised instead of the
original exception). :attr:`SessionEngine.stop_outcome` says what was
confirmed and what reached the disk.

Rendering and estimation are pluggable: a :class:`SessionObserver` sees every
record with the state it leads to, and every new live estimate; a
:class:`LiveEstimator` turns completed trials into an
:class:`~odohil.science.estimators.EstimateResult`. The estimate becomes JSON
only in its journal record.
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import Callable, Collection, Mapping
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from odohil import __version__
from odohil.driver.odometry import DriveSettings, OdometrySample, TrialMotion
from odohil.errors import (
    JournalError,
    MeasurementError,
    OdohilError,
    StopUnconfirmedError,
)
from odohil.science.estimators import EstimateResult, IncrementalEstimator, Observation
from odohil.science.floor_marks import PosePrior
from odohil.science.paths import Design
from odohil.science.pose_selection import SCALE_FLOOR_M, ParameterBelief, predictive_pose
from odohil.science.robot_description import RobotDescription
from odohil.session.journal.events import (
    FORMAT,
    Estimate,
    Event,
    Finished,
    MotionDone,
    MotionStart,
    Resumed,
    RobotConnected,
    SessionHeader,
    Solved,
    SourceEvent,
    StartPoseChecked,
    Stopped,
    StopUnconfirmed,
    TornRecordKept,
    TrialStart,
    Void,
)
from odohil.session.journal.file import Journal, Record, TornRecord
from odohil.session.journal.state import (
    CompletedTrial,
    OpenTrial,
    Phase,
    SessionState,
    apply,
    description_of_header,
    replay,
)
from odohil.session.measure.plausibility import far_window, judge
from odohil.session.measure.protocol import MeasuredPose, PoseSource, TrialContext
from odohil.session.plans.plan import Plan, driven_backward
from odohil.session.robots.protocol import Robot, SampleCallback
from odohil.session.robots.registry import parse_description as parse_robot_description
from odohil.session.run.start_pose import StartPose, check_start
from odohil.session.signals import (
    SignalReceived,
    motion_signals_raise,
    signal_name,
    signals_held,
)

StartCheck = Callable[[StartPose], None]
"""Judges where the robot stands before the session goes on: returns to go on
(after putting the robot back, say), raises to refuse."""

STOP_CONFIRM_TIMEOUT_S = 2.0
"""How long the engine waits, on the way out, for the robot to report it stopped, s."""


class SessionObserver(Protocol):
    """Sees the session unfold (a progress bar, the wizard, a report)."""

    def record(self, record: Record, state: SessionState) -> None:
        """``record`` was journaled; ``state`` is the session after it."""
        ...

    def estimated(self, result: EstimateResult, state: SessionState) -> None:
        """The live estimate is now ``result``: after its ``estimate`` record,
        and on resume once the trials of earlier processes are folded in."""
        ...


class LiveEstimator(Protocol):
    """Turns completed trials into the current estimate."""

    def add(self, trial: CompletedTrial) -> EstimateResult | None:
        """Fold one trial in; the current estimate, or None while too few
        trials make an estimate."""
        ...


@dataclass(frozen=True)
class MotionSettings:
    """How the robot drives each trial.

    Attributes:
        speeds: translation m/s, turning rad/s.
        accelerations: translation m/s^2, turning rad/s^2.
        step_timeout_s: longest wall time of one leg or turn, s.
        watchdog_s: the robot's own watchdog, s; it stops the robot when the
            host dies mid-motion; 0 leaves it off.
        settle_timeout_s: how long to wait for a robot found moving to stop, s.
        stop_timeout_s: on the way out, how long to wait for the robot to
            report that it stopped, s.
    """

    speeds: tuple[float, float] = (DriveSettings.speed_m_s, DriveSettings.turn_rate_rad_s)
    accelerations: tuple[float, float] = (
        DriveSettings.acceleration_m_s2,
        DriveSettings.turn_acceleration_rad_s2,
    )
    step_timeout_s: float = DriveSettings.step_timeout_s
    watchdog_s: float = DriveSettings.watchdog_s
    settle_timeout_s: float = 60.0
    stop_timeout_s: float = STOP_CONFIRM_TIMEOUT_S

    def drive_settings(self) -> DriveSettings:
        """What the robot backend is told."""
        return DriveSettings(
            speed_m_s=self.speeds[0],
            turn_rate_rad_s=self.speeds[1],
            acceleration_m_s2=self.accelerations[0],
            turn_acceleration_rad_s2=self.accelerations[1],
            step_timeout_s=self.step_timeout_s,
            watchdog_s=self.watchdog_s,
        )

    def to_json(self) -> dict[str, Any]:
        """The settings as a JSON object (SI units)."""
        return {
            "speeds": list(self.speeds),
            "accelerations": list(self.accelerations),
            "step_timeout_s": self.step_timeout_s,
            "watchdog_s": self.watchdog_s,
        }


def start_session(
    folder: str | Path,
    description_toml: str,
    plan: Plan,
    *,
    measure: str,
    settings: Mapping[str, Any],
    robot_path: str = "",
) -> tuple[Journal, SessionState]:
    """Create a session folder and journal its header and plan.

    Args:
        folder: the new session folder (must hold no journal).
        description_toml: the robot description's TOML text (journaled whole,
            so the session can be re-solved and re-estimated offline).
        plan: the designs and their trial counts.
        measure: the measurement source (``fake``, ``file:PATH``, ``operator``).
        settings: anything else worth keeping (port, seed, time scale...).
        robot_path: where the description was read from.

    Raises:
        JournalError: the folder already holds a session or cannot be written.
        RobotDescriptionError: the TOML is not a valid robot description.
    """
    parse_robot_description(description_toml, robot_path or "robot description")
    journal = Journal.create(folder)
    try:
        header = journal.write(
            SessionHeader(
                format=FORMAT,
                odohil=__version__,
                robot_toml=description_toml,
                robot_path=robot_path,
                measure=measure,
                settings=dict(settings),
                plan=plan,
            )
        )
        state = replay([header])
    except BaseException:
        journal.close()
        raise
    return journal, state


@dataclass(frozen=True)
class ResumedSession:
    """An existing session opened for appending.

    Attributes:
        journal: the open journal.
        state: the session as journaled.
        torn: the torn last record that was kept aside, if any.
    """

    journal: Journal
    state: SessionState
    torn: TornRecord | None


def open_to_resume(folder: str | Path) -> ResumedSession:
    """Open a session to continue it, without journaling the resume yet.

    The journal is locked (a second process on it sends nothing) and
    replayed; a torn last record is copied aside and cut from the journal,
    and that is journaled (``torn_record``: what was done to the file, true
    whether or not the resume goes on). No ``resumed`` record is written:
    the caller journals it with :func:`journal_resumed` once the robot has
    answered (odohil/session/run/opening.py), so that a resume whose port
    does not open or whose robot does not answer leaves no record claiming
    a resume that never happened.

    Raises:
        JournalError: no journal, in use, corrupt, or already finished.
    """
    journal, contents = Journal.open(folder)
    try:
        state = replay(contents.records)
        if state.finished:
            raise JournalError(f"the session in {folder} is finished; nothing to resume")
        if state.plan is None:
            raise JournalError(f"the session in {folder} has no plan")
        if contents.torn is not None:
            torn = contents.torn
            record = journal.write(
                TornRecordKept(
                    file=torn.set_aside.name if torn.set_aside else "",
                    line=torn.line_number,
                    bytes=torn.size,
                    reason=torn.reason,
                )
            )
            state = apply(state, record)
    except BaseException:
        journal.close()
        raise
    return ResumedSession(journal, state, contents.torn)


def journal_resumed(
    resumed: ResumedSession, note: Mapping[str, Any] | None = None
) -> ResumedSession:
    """``resumed`` with its ``resumed`` record journaled (``note``: what the
    resuming process says about itself): the resume has happened."""
    record = resumed.journal.write(Resumed(dict(note or {})))
    return replace(resumed, state=apply(resumed.state, record))


def resume_session(folder: str | Path, note: Mapping[str, Any] | None = None) -> ResumedSession:
    """Open a session to continue it and journal the resume at once
    (:func:`open_to_resume`, then :func:`journal_resumed`), for a caller with
    no robot to wait for; a session that drives a robot journals the resume
    only once the robot answered (odohil/session/run/opening.py).

    Raises:
        JournalError: no journal, in use, corrupt, or already finished.
    """
    resumed = open_to_resume(folder)
    try:
        return journal_resumed(resumed, note)
    except BaseException:
        resumed.journal.close()
        raise


def description_of(state: SessionState) -> RobotDescription:
    """The robot description journaled in the session header."""
    return description_of_header(state)


class IncrementalLiveEstimator:
    """A :class:`LiveEstimator` on the joint maximum-likelihood
    :class:`~odohil.science.estimators.IncrementalEstimator`."""

    def __init__(self, exclude: Collection[int] = frozenset()) -> None:
        self.inner = IncrementalEstimator()
        self.exclude = frozenset(exclude)

    def add(self, trial: CompletedTrial) -> EstimateResult | None:
        """Fold the trial in (unless its number is in ``exclude``); the current
        result, or None."""
        if trial.trial in self.exclude or not isinstance(trial.design, Design):
            # a general path's trial: the design estimator cannot fold it in
            return None if self.inner.fit is None else self.inner.result()
        observation = Observation(
            design=trial.design,
            pose_change=np.array(trial.pose_change, dtype=np.float64),
            measurement_cov=np.array(trial.cov, dtype=np.float64),
            line=trial.seq,
            trial=trial.trial,
        )
        if self.inner.add(observation) is None:
            return None
        return self.inner.result()


@dataclass(frozen=True)
class StopOutcome:
    """What the engine could check when a run ended early.

    Attributes:
        robot_stopped: the robot reported, after ``st``, that it stands still.
        detail: the encoder pose it stopped at, or why the stop is unconfirmed.
        journaled: the closing record (``stopped`` or ``stop_unconfirmed``) is
            on disk (appended and fsync-ed).
        journal_error: why the journal could not be written ("" when it was).
    """

    robot_stopped: bool
    detail: str
    journaled: bool
    journal_error: str = ""


class SessionEngine:
    """Runs the trials of one session (see the module docstring).

    Args:
        journal: the session's open journal.
        state: its state (from :func:`start_session` or :func:`resume_session`).
        robot: the connected robot (any backend behind the ``Robot`` protocol).
        source: where each trial's real pose change comes from.
        estimator: the live estimator, or None.
        observer: sees every record, or None.
        motion: how the robot drives.
        connection: what to journal about the connection (port, baud...).
        on_sample: sees every odometry sample of a motion (live read-outs).
        start_check: judges where the robot stands before the session goes on.
        belief: what every trial is predicted under (the floor-mark choice, the
            slip check), held for the whole run: a validation's calibration,
            which its held-out trials must not move. None: the live estimate,
            else the description's priors.
    """

    def __init__(
        self,
        journal: Journal,
        state: SessionState,
        robot: Robot,
        source: PoseSource,
        *,
        estimator: LiveEstimator | None = None,
        observer: SessionObserver | None = None,
        motion: MotionSettings | None = None,
        connection: Mapping[str, Any] | None = None,
        on_sample: SampleCallback | None = None,
        start_check: StartCheck | None = None,
        belief: ParameterBelief | None = None,
    ) -> None:
        if state.plan is None:
            raise JournalError("the session has no plan")
        self.journal = journal
        self.state = state
        self.plan: Plan = state.plan
        self.robot = robot
        self.description = description_of(state)
        self.source = source
        self.estimator = estimator
        self.observer = observer
        self.motion = motion or MotionSettings()
        self.connection = dict(connection or {})
        self.on_sample = on_sample
        self.start_check = start_check
        self.belief = belief
        self.latest_estimate: EstimateResult | None = None
        self.stop_outcome: StopOutcome | None = None
        self._predicted: PosePrior | None = None
        self._estimated = 0

    # -- journal ---------------------------------------------------------

    def _log(self, event: Event) -> Record:
        record = self.journal.write(event)
        self.state = apply(self.state, record)
        if self.observer is not None:
            self.observer.record(record, self.state)
        return record

    # -- the loop --------------------------------------------------------

    def run(self, max_trials: int | None = None) -> SessionState:
        """Run trials until the plan is done (or ``max_trials`` more completed).

        Returns the final state. On any exception (Ctrl-C and other signals
        included) the robot is stopped and the stop confirmed, the end
        journaled (see :meth:`_stopped`), and the exception re-raised.

        Raises:
            StopUnconfirmedError: the run ended early and the robot did not
                report that it stopped (the original exception is its cause).
        """
        try:
            self._catch_up_estimate()
            self._connect()
            self._check_start()
            self._finish_open_trial()
            completed = 0
            while (trial := self.state.next_trial()) is not None:
                if max_trials is not None and completed >= max_trials:
                    return self.state
                self._run_trial(trial)
                completed += 1
            self._log(Finished(n_trials=len(self.state.completed)))
        except BaseException as exc:
            if self._stopped(exc):
                raise
            assert self.stop_outcome is not None
            raise StopUnconfirmedError(self.stop_outcome.detail) from exc
        return self.state

    def _stopped(self, exc: BaseException) -> bool:
        """Stop the robot, confirm it, journal the end; whether it was confirmed.

        Further signals are held (not lost, not acted on) until this is done:
        the stop is bounded by ``stop_timeout_s`` and each record by its fsync.
        """
        if isinstance(exc, SignalReceived):
            reason = signal_name(exc.signum)
        elif isinstance(exc, KeyboardInterrupt):
            reason = "interrupted"
        else:
            reason = "error"
        # Never an exception's class name in the journal: it is read by people.
        message = str(exc) or ("Ctrl-C" if reason == "interrupted" else "an error with no message")
        with signals_held():
            try:
                sample = self.robot.stop_and_confirm(self.motion.stop_timeout_s)
            except StopUnconfirmedError as unconfirmed:
                stopped, detail, state = False, str(unconfirmed), None
            else:
                stopped, detail, state = True, sample.pose_text(), _sample_json(sample)
            try:
                opened = self.state.open_trial
                if opened is not None and opened.phase in (Phase.MARKED, Phase.MOVING):
                    self._log(
                        Void(
                            opened.trial,
                            opened.attempt,
                            reason=f"{reason} before the motion ended: {message}",
                        )
                    )
                if stopped:
                    self._log(Stopped(reason, message, robot="stopped", state=state))
                else:
                    self._log(StopUnconfirmed(reason, message, detail=detail))
            except (JournalError, OSError, ValueError) as failed:
                self.stop_outcome = StopOutcome(stopped, detail, False, str(failed))
            else:
                self.stop_outcome = StopOutcome(stopped, detail, True)
        return stopped

    def _catch_up_estimate(self) -> None:
        """Feed the trials completed in earlier processes to the estimator."""
        if self.estimator is None:
            return
        for trial in self.state.completed[self._estimated :]:
            if trial.ambiguous:
                continue
            with contextlib.suppress(OdohilError):
                self.latest_estimate = self.estimator.add(trial)
        self._estimated = len(self.state.completed)
        if self.latest_estimate is not None and self.observer is not None:
            self.observer.estimated(self.latest_estimate, self.state)

    def _connect(self) -> None:
        sample = self.robot.arm(self.motion.drive_settings())
        self._log(
            RobotConnected(
                connection=self.connection,
                motion=self.motion.to_json(),
                state=_sample_json(sample),
            )
        )

    def _check_start(self) -> None:
        """Where the robot stands against where the next trial starts: journaled
        (``start_pose``), then judged by ``start_check`` (which may put the robot
        back, or raise)."""
        start = check_start(self.state, self._settle())
        self._log(
            StartPoseChecked(
                trial=start.trial,
                expected=_pose(start.expected) if start.expected is not None else None,
                actual=_pose(start.actual),
                ok=start.ok,
            )
        )
        if self.start_check is not None:
            self.start_check(start)

    def _finish_open_trial(self) -> None:
        opened = self.state.open_trial
        if opened is None:
            return
        if opened.phase is Phase.MEASURING:
            self._measure()
            return
        where = "before its motion" if opened.phase is Phase.MARKED else "during its motion"
        self._log(
            Void(
                opened.trial,
                opened.attempt,
                reason=f"the session stopped {where}; the trial is redone",
            )
        )

    def _context(self, opened: OpenTrial, predicted: PosePrior | None = None) -> TrialContext:
        """What the source may know of the open attempt (its own readings included)."""
        return TrialContext(
            trial=opened.trial,
            attempt=opened.attempt,
            n_trials=self.plan.n_trials,
            design=self.plan.design_of(opened.trial),
            start=opened.start,
            end=opened.end,
            encoder_end_pose=opened.encoder_end_pose,
            predicted=predicted,
            readings=opened.readings,
        )

    def _settle(self) -> OdometrySample:
        return self.robot.settle(self.motion.settle_timeout_s)

    def _run_trial(self, trial: int) -> None:
        attempt = self.state.next_attempt(trial)
        design_index = self.plan.design_index(trial)
        design = self.plan.design_of(trial)  # as driven: one-way trials alternate
        self._settle()
        zeroed = self.robot.zero()
        ctx = TrialContext(trial=trial, attempt=attempt, n_trials=self.plan.n_trials, design=design)
        start = dict(self.source.at_start(ctx))
        self._log(
            TrialStart(
                trial,
                attempt,
                design=design_index,
                backward=driven_backward(design),
                zeroed=_sample_json(zeroed),
                start=start,
            )
        )
        with motion_signals_raise():  # Ctrl-Z mid-motion stops the robot, not odohil alone
            self._log(MotionStart(trial, attempt))
            record = self.robot.drive(design, self.motion.drive_settings(), self.on_sample)
        opened = self.state.open_trial
        assert opened is not None
        ctx = replace(
            self._context(opened),
            encoder_end_pose=record.end_pose,
            far_s=far_window(record),
        )
        end = dict(self.source.at_end(ctx))
        self._log(
            MotionDone(
                trial,
                attempt,
                encoder_end_pose=_pose(record.end_pose),
                duration_s=record.duration_s,
                trajectory=_trajectory(record),
                end=end,
            )
        )
        self._measure()

    def _belief(self) -> ParameterBelief:
        """The given belief, else the current estimate as a belief, else the
        description's priors."""
        if self.belief is not None:
            return self.belief
        priors = self.description.priors
        exact = self.description.robot.turns_exact
        if self.latest_estimate is None:
            return ParameterBelief.from_priors(priors, turns_exact=exact)
        try:
            return ParameterBelief.from_result(self.latest_estimate, priors, turns_exact=exact)
        except OdohilError:
            return ParameterBelief.from_priors(priors, turns_exact=exact)

    def _source_log(self, event: SourceEvent) -> TrialContext:
        """The :class:`~odohil.session.measure.protocol.MeasurementLog` given to the source."""
        self._log(event)
        opened = self.state.open_trial
        assert opened is not None
        return self._context(opened, self._predicted)

    def _measure(self) -> None:
        """Ask the source for the pose change (it journals its readings), journal
        it (``solved``) and update the live estimate (``estimate``)."""
        opened = self.state.open_trial
        assert opened is not None
        assert opened.encoder_end_pose is not None
        design = self.plan.design_of(opened.trial)  # as driven: one-way trials alternate
        predicted = predictive_pose(design, self._belief(), opened.encoder_end_pose)
        self._predicted = predicted
        try:
            ctx = self._context(opened, self._predicted)
            measured = self.source.pose_change(ctx, self._source_log)
        finally:
            self._predicted = None
        nominal_end = design.path().encoder_end_pose()
        judged = judge(
            opened.trial,
            measured,
            predicted,
            opened.encoder_end_pose,
            opened.trajectory,
            closed=math.hypot(nominal_end[0], nominal_end[1]) < SCALE_FLOOR_M,
        )
        if judged.refusal:  # void: the trial is redone once the measurement is fixed
            self._log(Void(opened.trial, opened.attempt, reason=judged.refusal))
            raise MeasurementError(judged.refusal)
        measured = judged.measured
        self._log(_solved(opened, measured))
        if self.state.completed[-1].ambiguous:
            self._estimated = len(self.state.completed)
            return
        if self.estimator is not None:
            n_completed = len(self.state.completed)
            n_trials = sum(1 for t in self.state.completed if not t.ambiguous)
            try:
                result = self.estimator.add(self.state.completed[-1])
            except OdohilError as exc:
                # the live estimate is a display aid: a fit that fails on few
                # trials must not stop the session (the trial is journaled)
                self._estimated = n_completed
                self._log(Estimate(n_trials, result=None, error=str(exc)))
                return
            self._estimated = n_completed
            self.latest_estimate = result
            if result is not None:
                self._log(Estimate(n_trials, result=result.to_json_dict()))
                if self.observer is not None:
                    self.observer.estimated(result, self.state)


def _solved(opened: OpenTrial, measured: MeasuredPose) -> Solved:
    """The ``solved`` event of a measured pose."""
    cov = measured.covariance
    return Solved(
        opened.trial,
        opened.attempt,
        pose_change=_pose(measured.pose),
        cov=(_pose(cov[0]), _pose(cov[1]), _pose(cov[2])),
        clear_cut=bool(measured.clear_cut),
        reason=measured.note,
        flag_reason=(measured.flag_reason or "flagged by the measurement source")
        if measured.flagged
        else None,
        ambiguous=True if measured.ambiguous else None,
        candidates=tuple(_pose(c) for c in measured.candidates) if measured.ambiguous else None,
        details=dict(measured.details),
    )


def _pose(values: Any) -> tuple[float, float, float]:
    """Three numbers as a pose (x m, y m, theta rad) of floats."""
    x, y, theta = (float(v) for v in values)
    return (x, y, theta)


def _sample_json(sample: OdometrySample) -> dict[str, Any]:
    return {
        "x_m": sample.x_m,
        "y_m": sample.y_m,
        "theta_rad": sample.theta_rad,
        "robot_time_s": sample.robot_time_s,
        "moving": sample.moving,
    }


def _trajectory(record: TrialMotion) -> tuple[tuple[float, ...], ...]:
    """Rows (t s since the run's first sample, x m, y m, heading rad)."""
    t0 = record.samples[0].robot_time_s if record.samples else 0.0
    return tuple(
        (round(s.robot_time_s - t0, 3), s.x_m, s.y_m, s.theta_rad)
        for s in record.samples
        if math.isfinite(s.robot_time_s)
    )


ObserverCallback = Callable[[Record, SessionState], None]


class CallbackObserver:
    """A :class:`SessionObserver` from a plain function."""

    def __init__(self, callback: ObserverCallback) -> None:
        self.callback = callback

    def record(self, record: Record, state: SessionState) -> None:
        """Pass the record on."""
        self.callback(record, state)

    def estimated(self, result: EstimateResult, state: SessionState) -> None:
        """Records only: the estimate is in its ``estimate`` record."""
