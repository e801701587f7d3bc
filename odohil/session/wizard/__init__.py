"""The operator at the robot: ``odohil wizard``.

- dialogue.py: ``OperatorDialogue``, ``guided_run``: the guided session;
- tape_entry.py: what a typed line means;
- validate.py: ``odohil wizard --validate``;
- motion_steps.py: the motion, step by step; observables.py: phi1..phi5 after each trial;
- interrupts.py: Ctrl-C beside a moving robot.

Import from the modules; each module's ``__all__`` is its face.
"""

__all__ = [
    "dialogue",
    "interrupts",
    "motion_steps",
    "observables",
    "tape_entry",
    "validate",
]
