"""The exit statuses of every odohil command, in one place.

| status | meaning |
|---|---|
| 0 | done; an estimate, if one is printed, is trusted |
| 1 | an error stopped the command (the message says which) |
| 2 | bad input: an option, file or session that cannot be used; nothing moved |
| 3 | not trusted or no estimate (nothing exported without --force) |
| 4 | the robot's stop could not be confirmed: it may still be moving |
| 128 + N | ended by signal N after the robot was stopped |

A failed pre-flight check (odohil/session/run/checks.py) exits by its
class (:func:`exit_for_check`), the same from run, resume, demo, validate and
the wizard: 2 bad input, 1 an error (a port or stream that does not answer);
either way nothing moved. A session run exits by how it ended
(:func:`exit_for_run`).

Status 3: the verdict is doubtful or failed, or the trials give no estimate
(too few, or every one left out); for report and export also a trusted
estimate too imprecise to export (odohil/session/results/outcome.py). Every command
that estimates maps its outcome through :func:`exit_for_outcome`.

128 + N: 130 Ctrl-C (SIGINT), 143 SIGTERM, 129 SIGHUP, 131 SIGQUIT.
"""

from __future__ import annotations

import signal
from typing import TYPE_CHECKING

from odohil.session.results.outcome import EstimateOutcome

if TYPE_CHECKING:
    from odohil.session.run import PreflightCheck, RunOutcome

EXIT_OK = 0
EXIT_ERROR = 1
EXIT_BAD_INPUT = 2
EXIT_UNTRUSTED = 3
EXIT_STOP_UNCONFIRMED = 4
EXIT_INTERRUPTED = 128 + signal.SIGINT


def exit_for_signal(signum: int) -> int:
    """The exit status after a signal ended the command (128 + the signal number)."""
    return 128 + int(signum)


def exit_for_outcome(outcome: EstimateOutcome, export: bool = False) -> int:
    """The exit status of a command that estimates: 0 when the estimate is
    trusted (and, for a command that exports, precise enough to export), else 3."""
    ok = outcome.exportable if export else outcome.trusted
    return EXIT_OK if ok else EXIT_UNTRUSTED


def exit_for_check(check: PreflightCheck) -> int:
    """The exit status of a failed pre-flight check: 2 bad input, 1 error."""
    return EXIT_BAD_INPUT if check.exit_class == "bad input" else EXIT_ERROR


def exit_for_run(outcome: RunOutcome) -> int:
    """The exit status of a session run: a finished one by its verdict
    (:func:`exit_for_outcome`), else 128 + the signal, 4 stop unconfirmed, 1 error."""
    if outcome.status == "finished":
        return exit_for_outcome(outcome.estimate)
    if outcome.status == "stop unconfirmed":
        return EXIT_STOP_UNCONFIRMED
    if outcome.status == "interrupted" and outcome.signal is not None:
        return exit_for_signal(outcome.signal)
    return EXIT_ERROR
