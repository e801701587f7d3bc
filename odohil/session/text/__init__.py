"""The words every command prints, computed apart from rendering them.

- outcome.py: the verdict line, refusals and notes of an estimate;
- run.py: what a run says as it goes (``RunWatch``, ``Said``, ``run_ended``);
- operator.py: what the wizard says to the operator.

Import from the modules; each module's ``__all__`` is its face.
"""

__all__ = [
    "operator",
    "outcome",
    "run",
]
