"""Pre-flight checks of a session's inputs, made before any session folder is
created or any port opened: the plan against what the wire carries, the robot
description, the session folder, and a trial file against the plan.

Every check raises an :class:`~odohil.errors.OdohilError` whose message names
the option or file and what is accepted; nothing has moved yet.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from odohil import units
from odohil.errors import OdohilError, ParameterError, TrialFileError
from odohil.science.estimators.checks import plan_problems
from odohil.science.planner import DEFAULT_MIN_TRIALS_PER_DESIGN
from odohil.science.robot_description import RobotDescription
from odohil.session.floor_space import check_floor
from odohil.session.plan import Plan, check_session_plan, parse_plan
from odohil.session.robot_file import read_robot_toml
from odohil.session.robots import parse_description as parse_robot_description
from odohil.session.trial_files import read_trials


@dataclass(frozen=True)
class Checked:
    """The inputs of a new session, validated.

    Attributes:
        plan: the plan (legs within the wire range, trial counts within caps).
        description: the robot description.
        toml: its TOML text, as journaled.
    """

    plan: Plan
    description: RobotDescription
    toml: str


def check_new_session(
    plan_text: str, robot_file: Path, session: Path | None, allow_turns: bool = False
) -> Checked:
    """Validate ``--plan``, ``--robot`` and ``--session`` of a new session; a
    design without a variant gets the robot's default (:func:`default_variant`).

    Raises:
        ParameterError: a bad plan, a ``turn`` design the robot refuses
            (:func:`check_turns`), a plan the estimator cannot use
            (:func:`check_estimable`) or a ``--session`` that is not a folder.
        RobotDescriptionError: the robot description cannot be read or is invalid.
    """
    toml = read_robot_toml(robot_file, what="--robot: robot description")
    description = parse_robot_description(toml, source=str(robot_file))
    try:
        plan = check_session_plan(
            parse_plan(plan_text, default_variant(description)), description.robot.protocol
        )
    except ParameterError as exc:
        raise ParameterError(f"--plan: {exc}") from None
    check_turns(plan, description, allow_turns)
    check_estimable(plan, description)
    check_session_folder(session)
    return Checked(plan=plan, description=description, toml=toml)


def default_variant(description: RobotDescription) -> str:
    """``turn`` for a robot whose in-place turns are exact, else ``reverse``."""
    return "turn" if description.robot.turns_exact else "reverse"


def turn_designs(plan: Plan, description: RobotDescription) -> list[str]:
    """Labels of the plan's ``turn`` designs when the robot's turns carry error
    (``[robot] turns_exact = false``); empty otherwise."""
    if description.robot.turns_exact:
        return []
    return [i.design.label() for i in plan.items if i.design.variant == "turn"]


def check_turns(plan: Plan, description: RobotDescription, allow_turns: bool) -> None:
    """Refuse ``turn`` designs on a robot whose turns carry error, unless
    ``allow_turns`` (ParameterError naming ``--plan`` and ``--allow-turns``)."""
    turns = turn_designs(plan, description)
    if turns and not allow_turns:
        raise ParameterError(
            f"--plan asks for in-place turns ({', '.join(turns)}) but this robot's turns "
            "carry error ([robot] turns_exact = false): turn trials bias E_R and K_theta "
            "while looking consistent. Use variant=reverse (the default for this robot), "
            "or give --allow-turns to run them anyway (the estimate is then not trusted)"
        )


def check_estimable(plan: Plan, description: RobotDescription) -> None:
    """Refuse a plan whose trials, all driven, could give no estimate of the four
    parameters (:func:`odohil.science.estimators.checks.plan_problems`, at the
    description's ``[priors]``): ParameterError naming ``--plan``, the reason and
    what would make it estimable."""
    problems = plan_problems(
        [(item.design, item.n_trials) for item in plan.items], description.priors.mean
    )
    if problems:
        raise ParameterError(
            f"--plan {plan.to_text()}: no estimate could come of these trials (nothing "
            "was driven): " + "; ".join(problems)
        )


def check_trials_per_design(
    plan: Plan,
    allow_few: bool,
    min_trials_per_design: int = DEFAULT_MIN_TRIALS_PER_DESIGN,
) -> None:
    """Refuse a plan with a design of fewer trials than the planner's minimum
    for honest intervals, unless ``allow_few`` (ParameterError naming
    ``--plan`` and ``--allow-few-trials``): such a session's estimate cannot
    be exported without ``--force`` (odohil/session/outcome.py)."""
    few = [
        f"{i.design.label()} (n={i.n_trials})"
        for i in plan.items
        if i.n_trials < min_trials_per_design
    ]
    if few and not allow_few:
        raise ParameterError(
            f"--plan has fewer than {units.plural(min_trials_per_design, 'trial')} a design "
            f"({', '.join(few)}), the planner's minimum for honest intervals: its estimate "
            "could not be exported. Give n >= "
            f"{min_trials_per_design} for every design, or --allow-few-trials to run it anyway"
        )


def check_session_folder(session: Path | None) -> None:
    """A ``--session`` that exists must be a folder, and a symbolic link must
    lead somewhere (ParameterError otherwise)."""
    if session is not None and session.is_symlink() and not session.exists():
        raise ParameterError(
            f"--session {session} is a symbolic link to {os.readlink(session)}, which does "
            "not exist: create that folder, or give another --session"
        )
    if session is not None and session.exists() and not session.is_dir():
        raise ParameterError(
            f"--session {session} is a file, not a session folder: give a new or "
            "existing session folder"
        )


def check_trial_file(
    path: str | Path, description: RobotDescription, plan: Plan, first_trial: int = 1
) -> None:
    """A trial file that serves the plan: one row per trial, row k of trial k's
    design, for trials ``first_trial`` .. the plan's last.

    Raises:
        TrialFileError: the file is unreadable, has bad rows, too few rows or a
            row of another design (the first few are listed).
    """
    trials = read_trials(path, description)
    if len(trials) < plan.n_trials:
        raise TrialFileError(
            f"--measure {path}: {len(trials)} row(s) for a plan of "
            f"{units.plural(plan.n_trials, 'trial')}; "
            "the file needs one row per trial, in plan order"
        )
    wrong = []
    for trial in range(first_trial, plan.n_trials + 1):
        row = trials.trials[trial - 1]
        wanted = plan.design_of(trial)
        if row.design != wanted:
            wrong.append(
                f"row {trial} (line {row.line}) is {row.design.label()}, "
                f"trial {trial} runs {wanted.label()}"
            )
    if wrong:
        shown = "\n  ".join(wrong[:5]) + (
            f"\n  ... {len(wrong) - 5} more" if len(wrong) > 5 else ""
        )
        raise TrialFileError(
            f"--measure {path}: {len(wrong)} row(s) of another design than the plan's:\n  {shown}"
        )


# --- the checks as values (the wizard shows them as ticks) ---------------------


@dataclass(frozen=True)
class Check:
    """One pre-flight check: its name, whether it passed, and what was found."""

    name: str
    ok: bool
    detail: str


def leg_check(plan: Plan, max_leg_m: float) -> Check:
    """Do the plan's legs fit the floor (``--max-leg-m``)? What one move
    command carries is the robot's own limit, checked with the plan
    (:func:`~odohil.session.plan.check_session_plan`), not here."""
    problems = [
        f"{item.design.label()}: legs of {item.design.l_m:g} m exceed {max_leg_m:g} m"
        for item in plan.items
        if item.design.l_m > max_leg_m
    ]
    detail = (
        "; ".join(problems)
        if problems
        else f"{units.plural(plan.n_trials, 'trial')}, {plan.distance_m:.1f} m of driving "
        f"({plan.to_text()})"
    )
    return Check("plan feasible", not problems, detail)


def estimable_check(plan: Plan, description: RobotDescription) -> Check:
    """:func:`check_estimable` as a check."""
    try:
        check_estimable(plan, description)
    except OdohilError as exc:
        return Check("plan estimable", False, str(exc))
    return Check("plan estimable", True, "its trials can identify the four parameters")


def floor_check(plan: Plan, description: RobotDescription) -> Check:
    """Does the plan fit the robot description's free floor ([floor] length_m)?"""
    try:
        check_floor(plan, description)
    except OdohilError as exc:
        return Check("floor space", False, str(exc))
    given = description.floor_length_m
    limit = f"of {given:g} m" if given is not None else "(no [floor] length_m given)"
    return Check("floor space", True, f"the plan needs {plan.excursion_m:g} m of floor {limit}")
