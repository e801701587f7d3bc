"""The exit statuses of every odohil command, in one place.

| status | meaning |
|---|---|
| 0 | done; an estimate, if one is printed, is trusted |
| 1 | an error stopped the command (the message says which) |
| 2 | bad input: an option, file or session that cannot be used; nothing moved |
| 3 | an estimate is printed but its verdict is doubtful or failed |
| 4 | the robot's stop could not be confirmed: it may still be moving |
| 128 + N | ended by signal N after the robot was stopped |

128 + N: 130 Ctrl-C (SIGINT), 143 SIGTERM, 129 SIGHUP, 131 SIGQUIT.
"""

from __future__ import annotations

import signal

EXIT_OK = 0
EXIT_ERROR = 1
EXIT_BAD_INPUT = 2
EXIT_UNTRUSTED = 3
EXIT_STOP_UNCONFIRMED = 4
EXIT_INTERRUPTED = 128 + signal.SIGINT


def exit_for_signal(signum: int) -> int:
    """The exit status after a signal ended the command (128 + the signal number)."""
    return 128 + int(signum)
