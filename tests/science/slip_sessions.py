"""Simulated sessions for the slip check on clean tape (issue 31): shared by
tests/science/test_slip_check_robots.py, tests/science/test_slip_check_paths.py,
bench/slip_check.py and bench/slip_check_paths.py.

Each trial: the true pose change from the discrete model
(odohil/science/simulator.py; with a differential drive's turn errors,
odohil/science/diff_drive.py ``simulate_turn_errors``), its five floor-mark
distances read with 1 mm Gaussian noise, predicted as a session predicts it
(odohil/session/run/engine.py ``_belief``: the given belief, else the live
estimate as a belief, else the priors), solved and checked by
odohil/science/pose_selection.py. A clean trial counts as a **false alarm**
when it trips the check; the same readings with one distance (at random) off
by +-:data:`SLIP_M` count as **caught** when they trip it (or no rigid motion
explains them). The live estimate is fed the clean trial's solution.
"""

from __future__ import annotations

import contextlib
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from odohil.errors import OdohilError
from odohil.science.diff_drive import simulate_turn_errors
from odohil.science.estimators import IncrementalEstimator, Observation
from odohil.science.estimators.paths import estimate_paths
from odohil.science.estimators.result import EstimateResult
from odohil.science.floor_marks import MarkDistances, MarkSolution, marks_from_pose
from odohil.science.moments import TurnErrors
from odohil.science.parameters import ErrorParameters
from odohil.science.path_designs import PathDesign
from odohil.science.path_trials import PathTrial
from odohil.science.paths import Design, floor_choreography
from odohil.science.pose_selection import ParameterBelief, predictive_pose, select_pose
from odohil.science.robot_description import (
    ParameterPriors,
    RobotDescription,
    RobotSettings,
    Screw,
)
from odohil.science.simulator import simulate

SLIP_M = 0.005
"""The operator's slip the check should catch, m."""
NOMAD_SCREWS = (Screw("A", 0.2, 0.0), Screw("B", -0.1, 0.173), Screw("C", -0.1, -0.173))
CREATE2_SCREWS = (Screw("A", 0.15, 0.0), Screw("B", -0.075, 0.13), Screw("C", -0.075, -0.13))
CROSS = (("A", "B"), ("B", "C"))
GRID = {  # paper units: E_R deg/m, E_T, K_theta deg^2/m, K_rho m
    "Nomad 150": (-0.202, -0.02, 0.012, 3.6e-5),
    "real robot": (-0.15, -0.02, 0.39, 3.6e-5),
    "E_R -1, K_th 0.5": (-1.0, -0.02, 0.5, 3.6e-5),
    "-2, +5 %, 1, 1e-6": (-2.0, 0.05, 1.0, 1e-6),
    "+2, -5 %, 1, 1e-3": (2.0, -0.05, 1.0, 1e-3),
    "+2, +5 %, 0.001, 1e-6": (2.0, 0.05, 0.001, 1e-6),
    "-2, -5 %, 0.001, 1e-3": (-2.0, -0.05, 0.001, 1e-3),
}
"""The robots of the benches: the paper's Nomad, the real robot of the paper's
data and corners of issue 31's grid (E_R to +-2 deg/m, E_T to +-5 %, K_theta
0.001-1 deg^2/m, K_rho 1e-6-1e-3 m)."""


@dataclass(frozen=True)
class SimRobot:
    """A robot of the benches (odohil/robots/*.toml).

    Attributes:
        name: for tables.
        screws: its marking screws (m).
        turns_exact: the description's ``turns_exact``.
        turns: the true turn errors (exact for a synchronous drive).
        variant: the forth-and-back motion its plans drive.
    """

    name: str
    screws: tuple[Screw, ...]
    turns_exact: bool
    turns: TurnErrors = field(default_factory=TurnErrors)
    variant: str = "turn"


NOMAD = SimRobot("Nomad 150", NOMAD_SCREWS, True)
CREATE2 = SimRobot(
    "Create 2", CREATE2_SCREWS, False, TurnErrors.uniform(0.012, 2e-4), "reverse"
)  # the fake Create 2's default e_turn and K_spin (fakes/create2/config.py)


@dataclass
class Tally:
    """Counts of one cell: trials, clean trials tripped, slipped trials caught."""

    trials: int = 0
    tripped: int = 0
    caught: int = 0
    tripped_at: list[int] = field(default_factory=list)
    """The tripped clean trials' places (1-based) among the counted ones."""

    def add(self, other: Tally) -> None:
        """Add ``other``'s counts to these."""
        self.trials += other.trials
        self.tripped += other.tripped
        self.caught += other.caught
        self.tripped_at.extend(other.tripped_at)


def description_of(robot: SimRobot, priors: ParameterPriors) -> RobotDescription:
    """The robot's description with ``priors``, 1 mm tape, two cross distances."""
    settings = RobotSettings(turns_exact=robot.turns_exact)
    return RobotDescription(robot.screws, 0.001, CROSS, priors=priors, robot=settings)


def priors_for(truth: ErrorParameters, given: bool) -> ParameterPriors:
    """``[priors]`` at the robot's own values with the default deviations, or none."""
    return ParameterPriors(mean=truth, given=True) if given else ParameterPriors()


def check_trial(
    description: RobotDescription,
    design: Design | PathDesign,
    truth: ErrorParameters,
    turns: TurnErrors,
    belief: ParameterBelief,
    rng: np.random.Generator,
    tally: Tally,
) -> MarkSolution | None:
    """One trial, clean and slipped, checked under ``belief``; counted in
    ``tally``. Returns the clean trial's solution (None when no rigid motion
    explains the clean readings, the tape's own test, or it is ambiguous)."""
    path = design.path()
    if turns.exact:
        pose = simulate(path, truth, 1, seed=rng).pose_change[0]
    else:
        pose = simulate_turn_errors(path, truth, turns, 1, seed=rng).pose_change[0]
    exact = marks_from_pose(description, pose).as_array()
    readings = exact + rng.normal(0.0, description.sigma_m, exact.size)
    odometry = path.encoder_end_pose()
    predicted = predictive_pose(design, belief, odometry)
    try:
        clean = select_pose(
            description, MarkDistances.of(description, readings), odometry, predicted
        )
    except OdohilError:
        return None
    tally.trials += 1
    tally.tripped += clean.slip.tripped
    if clean.slip.tripped:
        tally.tripped_at.append(tally.trials)
    slipped = readings.copy()
    slipped[int(rng.integers(slipped.size))] += SLIP_M * float(rng.choice((-1.0, 1.0)))
    try:
        tally.caught += select_pose(
            description, MarkDistances.of(description, slipped), odometry, predicted
        ).slip.tripped
    except OdohilError:
        tally.caught += 1  # refused as no rigid motion: caught too
    return None if clean.ambiguous else clean.solution


def forth_back_session(
    truth: ErrorParameters,
    robot: SimRobot,
    given: bool,
    plan: Sequence[tuple[float, float, int]],
    rng: np.random.Generator,
) -> Tally:
    """A session of forth-and-back designs ((k, l, n) in driving order, in
    ``robot.variant``, one-way trials alternating as a session drives them),
    predicted under the running incremental estimate (the priors before it)."""
    priors = priors_for(truth, given)
    description = description_of(robot, priors)
    variant = robot.variant
    choreography = floor_choreography([(Design(k, length, variant), n) for k, length, n in plan])  # type: ignore[arg-type]
    estimator = IncrementalEstimator()
    tally = Tally()
    for trial in range(1, choreography.n_trials + 1):
        design = choreography.trial(trial)[0]
        belief = ParameterBelief.from_priors(priors)
        if estimator.fit is not None:
            with contextlib.suppress(OdohilError):
                belief = ParameterBelief.from_result(estimator.result(), priors)
        solution = check_trial(description, design, truth, robot.turns, belief, rng, tally)
        if solution is not None:
            observation = Observation(design, solution.pose_change, solution.cov, trial=trial)
            with contextlib.suppress(OdohilError):
                estimator.add(observation)
    return tally


PlanItem = tuple[Design | PathDesign, int]


def driven(plan: Sequence[PlanItem]) -> list[Design | PathDesign]:
    """Every trial's design as a session drives it (one-way forth-and-back
    trials alternate direction; general paths as given)."""
    out: list[Design | PathDesign] = []
    for design, n in plan:
        if isinstance(design, Design):
            choreography = floor_choreography([(design, n)])
            out.extend(choreography.trial(i)[0] for i in range(1, n + 1))
        else:
            out.extend([design] * n)
    return out


def path_trial(design: Design | PathDesign, solution: MarkSolution, trial: int) -> PathTrial:
    """A solved trial as the recipe fits it (odohil/session/journal/state.py
    ``session_path_trials``; the encoders end on their nominal pose here)."""
    family: str = design.kind if isinstance(design, PathDesign) else design.forward.label()
    direction = design.direction if isinstance(design, PathDesign) else "mixed"
    return PathTrial(
        path=design.path(),
        pose_change=solution.pose_change,
        measurement_cov=solution.cov,
        trial=trial,
        family=family,
        direction=direction,  # type: ignore[arg-type]
    )


@dataclass(frozen=True)
class PathSession:
    """What one general-path calibration session and its validation gave.

    Attributes:
        calibration: the calibration trials' counts.
        validation: the validation trials' counts.
        estimate: the calibration's last live estimate (None: too few trials).
    """

    calibration: Tally
    validation: Tally
    estimate: EstimateResult | None


def path_session(
    truth: ErrorParameters,
    robot: SimRobot,
    given: bool,
    plan: Sequence[PlanItem],
    validate: Sequence[PlanItem],
    rng: np.random.Generator,
    *,
    unknown_turns: bool = True,
) -> PathSession:
    """A calibration session of a plan with general paths, predicted under the
    recipe's fit of every trial so far (odohil/session/run/running.py
    ``PathBeliefEstimator``: robust, Wald intervals; the priors before it),
    then a validation of ``validate`` predicted under the calibration's last
    estimate (``validation_calibration``; skipped when there is none).
    ``unknown_turns`` False: the belief's turns as before issue 31 (exact
    where no estimate pins them, whatever the robot), for a before/after."""
    priors = priors_for(truth, given)
    description = description_of(robot, priors)
    exact = robot.turns_exact or not unknown_turns
    trials: list[PathTrial] = []
    estimate: EstimateResult | None = None
    calibration = Tally()
    for number, design in enumerate(driven(plan), 1):
        belief = ParameterBelief.from_priors(priors, turns_exact=exact)
        if estimate is not None:
            with contextlib.suppress(OdohilError):
                belief = ParameterBelief.from_result(estimate, priors, turns_exact=exact)
        solution = check_trial(description, design, truth, robot.turns, belief, rng, calibration)
        if solution is None:
            continue
        trials.append(path_trial(design, solution, number))
        try:
            estimate = estimate_paths(trials, turns_exact=robot.turns_exact, intervals="wald")
        except OdohilError:
            estimate = None
    validation = Tally()
    if estimate is not None and validate:
        belief = ParameterBelief.from_result(estimate, priors, turns_exact=exact)
        for design in driven(validate):
            check_trial(description, design, truth, robot.turns, belief, rng, validation)
    return PathSession(calibration, validation, estimate)
