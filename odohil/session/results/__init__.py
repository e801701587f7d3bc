"""The one recipe from a session or a trial file to an estimate, and what it feeds.

- outcome.py: ``estimate_state``, ``estimate_source``: the estimate and its verdict;
- validation.py: held-out trials and their test;
- exports.py: the filter exports (ROS 2 diff-drive, odometry message, ...);
- report/: the session report (its page, plots and exported files).

Importing this package imports none of them (the estimators are heavy):
import from the modules; each module's ``__all__`` is its face.
"""

__all__ = [
    "exports",
    "outcome",
    "report",
    "validation",
]
