"""``odohil validate --detect NAME=VALUE[,NAME=VALUE]``: as many validation
trials as it takes to catch a calibration error (issue 31).

Each named error is the difference between the robot's true parameter and
the calibration's estimate, in the paper's units as every parameter option
takes them (E_R deg/m, E_T a plain number or a percentage ``2%``, K_theta
deg^2/m, K_rho m, a general-path fit's e_turn... as E_T, K_spin deg^2/deg;
odohil/units.py converts). For each alone, the fewest trials of the path are
found whose best test of the eight the verdict runs rejects the robot with
that error with probability 0.9 at the verdict's level (alpha / 8 per test;
odohil/science/validation_power.py ``trials_to_catch``: the predicted and the
true mean and covariance of one trial, the measurement's covariance and the
calibration's uncertainty by the delta method). The count planned is the
largest of them. A spread error (K_theta, K_rho, K_spin) must be positive:
the NEES tests are upper-tailed, a robot steadier than the model is never
rejected.

The measurement's covariance is predicted at the path's expected pose
change: a motion-capture stream's (``--measure tcp://``, two still poses with
the description's ``pose_sigma``), else the tape's (the floor-mark solver's,
odohil/science/floor_marks.py ``pose_covariance``: ``fake``, the operator's
tape, a trial file of distances).

With ``--trials N`` too, N is checked, not replaced: below power 0.9 it is
refused, naming the count that would do. When no count up to 10000 (the range
of ``--trials``) does, the path cannot: refused before anything moves, with the
best power and what would help. Only a driven path is sized: the trials of a
file are what they are (``what a pass rules out`` says what they catch).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

from odohil import units
from odohil.errors import ParameterError
from odohil.science.estimators import EstimateResult
from odohil.science.limits import RANGES
from odohil.science.parameters import PARAMETER_NAMES
from odohil.science.paths import EncoderPath
from odohil.science.robot_description import RobotDescription
from odohil.science.validation import (
    DETECTION_POWER,
    N_TESTS,
    PathPrediction,
    predict_fitted,
    predict_path,
)
from odohil.science.validation_power import (
    MAX_TRIALS,
    TrialPlan,
    trials_to_catch,
    verdict_power,
)
from odohil.session.measure.kinds import expected_pose_cov
from odohil.session.results.validation import (
    VARIANCE_RATES,
    ValidationPath,
    parameter_covariance,
    parameter_dofs,
    predict_calibrated,
)
from odohil.session.text.outcome import DETECT_HELP, DETECT_SYNTAX, sizing_lines, test_words

__all__ = [
    "DETECT_HELP",
    "DETECT_SYNTAX",
    "Detect",
    "Sizing",
    "parse_detect",
    "size_validation",
    "sizing_lines",
]


@dataclass(frozen=True)
class Detect:
    """One error ``--detect`` names.

    Attributes:
        name: the parameter (E_R, E_T, K_theta, K_rho, or a fit's e_turn..., K_spin).
        shift: true minus estimated value, SI.
    """

    name: str
    shift: float

    def text(self) -> str:
        """For people: ``E_R off by 0.4 deg/m``."""
        return f"{self.name} off by {units.paper_text(self.name, self.shift)}"


def parse_detect(text: str, names: tuple[str, ...] = PARAMETER_NAMES) -> tuple[Detect, ...]:
    """``--detect``: NAME=VALUE pairs, comma separated, in the paper's units
    (module docstring); ``names`` the calibration's parameters.

    Raises:
        ParameterError: naming ``--detect``, the accepted names and form.
    """
    found: dict[str, Detect] = {}
    for part in (p.strip() for p in text.split(",")):
        name, equals, value = (s.strip() for s in part.partition("="))
        if not equals or name not in names:
            raise ParameterError(
                f"--detect {text!r}: {part!r} is not NAME=VALUE with NAME one of "
                f"{', '.join(names)}; give {DETECT_SYNTAX}"
            )
        percent = value.endswith("%")
        if percent and not (name == "E_T" or units.parameter_kind(name) == "e_turn"):
            raise ParameterError(f"--detect {part}: only E_T and e_turn take a percentage")
        try:
            number = float(value.removesuffix("%"))
        except ValueError:
            raise ParameterError(f"--detect {part}: {value!r} is not a number") from None
        shift = units.parameter_from_paper(name, number / 100 if percent else number)
        if not (math.isfinite(shift) and shift != 0.0):
            raise ParameterError(f"--detect {part}: the error must be finite and not 0")
        if name in VARIANCE_RATES and shift < 0:
            raise ParameterError(
                f"--detect {part}: a spread error must be positive (the robot's {name} "
                "larger than the calibration's): the NEES tests never reject a robot "
                "steadier than the model"
            )
        if name in found:
            raise ParameterError(f"--detect {text!r}: {name} named twice")
        found[name] = Detect(name, shift)
    return tuple(found.values())


@dataclass(frozen=True)
class Caught:
    """How one error is caught.

    Attributes:
        detect: the error.
        plan: the fewest trials (None: none up to the limit) and their power.
        power: the power of the trials chosen.
        test: the test that catches it at that count.
    """

    detect: Detect
    plan: TrialPlan
    power: float
    test: str


@dataclass(frozen=True)
class Sizing:
    """The trials a validation drives to catch the errors of ``--detect``.

    Attributes:
        trials: the count chosen (``--trials`` when given and enough).
        caught: per error, its plan and the power at ``trials``.
        given: whether ``--trials`` was given.
        path: the ``--path`` text.
    """

    trials: int
    caught: tuple[Caught, ...]
    given: bool
    path: str = ""

    def lines(self) -> list[str]:
        """What it prints before anything moves (:func:`sizing_lines`)."""
        return sizing_lines({"sizing": self.to_json_dict()})

    def to_json_dict(self) -> dict[str, Any]:
        """{"trials", "given", "path", "power": 0.9, "detect": {NAME: {"error",
        "trials", "power", "test"}}} (SI); a driven validation journals it in
        its header's ``settings`` as ``sizing``."""
        return {
            "trials": self.trials,
            "given": self.given,
            "path": self.path,
            "power": DETECTION_POWER,
            "detect": {
                c.detect.name: {
                    "error": c.detect.shift,
                    "trials": c.plan.trials,
                    "power": c.power,
                    "test": c.test,
                }
                for c in self.caught
            },
        }


def _truth(path: EncoderPath, calibration: EstimateResult, detect: Detect) -> PathPrediction:
    """One trial's prediction at the calibration's parameters but ``detect``'s."""
    names = [p.name for p in calibration.parameters]
    values = [p.value for p in calibration.parameters]
    if len(names) > len(PARAMETER_NAMES):
        values[names.index(detect.name)] += detect.shift
        return predict_fitted(path, names, values)
    params = calibration.params
    field = ("e_r", "e_t", "k_theta", "k_rho")[PARAMETER_NAMES.index(detect.name)]
    return predict_path(path, replace(params, **{field: getattr(params, field) + detect.shift}))


def size_validation(
    detect_text: str,
    vpath: ValidationPath,
    calibration: EstimateResult,
    description: RobotDescription,
    *,
    measure: str | None,
    trials: int | None,
    alpha: float,
) -> Sizing:
    """The trials to drive on ``vpath`` so that each error of ``detect_text``
    (``--detect``) is caught with probability 0.9 (module docstring); before
    anything moves.

    Raises:
        ParameterError: a malformed ``--detect``, a path that is not driven,
            ``--trials`` too few, or a path that cannot catch an error in
            10000 trials (the message gives the best power and what would help).
        RobotDescriptionError: motion capture without ``pose_sigma``.
    """
    names = tuple(p.name for p in calibration.parameters)
    found = parse_detect(
        detect_text, names if len(names) > len(PARAMETER_NAMES) else PARAMETER_NAMES
    )
    path = vpath.path
    if vpath.drivable is None or path is None:
        raise ParameterError(
            f"--detect sizes the trials a validation drives; the trials of --path {vpath.text} "
            "are given (what a pass rules out is printed with the verdict)"
        )
    if trials is not None:
        RANGES["plan_n"].check("--trials", trials)
    prediction = predict_calibrated(path, calibration)
    r = expected_pose_cov(measure, description, prediction.mean)
    sigma = parameter_covariance(calibration)
    nus = parameter_dofs(calibration)
    truths = [_truth(path, calibration, d) for d in found]
    plans = [
        trials_to_catch(
            prediction,
            truth,
            measurement_cov=r,
            parameter_cov=sigma,
            alpha=alpha,
            parameter_dofs=nus,
        )
        for truth in truths
    ]
    cannot = [(d, p) for d, p in zip(found, plans, strict=True) if p.trials is None]
    if cannot:
        raise ParameterError(
            f"--detect: {vpath.text} cannot catch "
            + "; ".join(
                f"{d.text()} with probability {DETECTION_POWER:g} in "
                f"{units.plural(MAX_TRIALS, 'trial')} (best {p.power:.3f}, {test_words(p.test)})"
                for d, p in cannot
            )
            + ". What would help: a longer path (its mean moves further with the error), a "
            "different path (one whose heading or position follows that parameter), or a "
            "more precise calibration (more calibration trials: its own uncertainty bounds "
            "what any number of validation trials can tell); or ask for a larger error"
        )
    needed = max(p.trials or 0 for p in plans)
    chosen = needed if trials is None else trials
    caught = []
    for d, p, truth in zip(found, plans, truths, strict=True):
        at = verdict_power(
            prediction, truth, chosen, measurement_cov=r, parameter_cov=sigma,
            level=alpha / N_TESTS, parameter_dofs=nus,
        )  # fmt: skip
        caught.append(Caught(d, p, at.power, at.test))
    if trials is not None and trials < needed:
        short = [c for c in caught if (c.plan.trials or 0) > trials]
        raise ParameterError(
            f"--trials {trials} with --detect: "
            + "; ".join(
                f"{c.detect.text()} is caught with probability {c.power:.3f} only" for c in short
            )
            + f"; {units.plural(needed, 'trial')} reach {DETECTION_POWER:g} "
            f"(give --trials {needed}, or leave --trials out and --detect chooses)"
        )
    return Sizing(chosen, tuple(caught), trials is not None, vpath.text)
