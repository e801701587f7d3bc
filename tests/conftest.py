"""Test-session set-up shared by every test file."""

from __future__ import annotations

import signal

import pytest

_INHERITED_IGNORE = (signal.SIGINT, signal.SIGQUIT, signal.SIGHUP)
"""Signals a shell leaves ignored for a job it starts in the background (and
nohup for SIGHUP). Ignored dispositions pass to every process the tests start,
so a test that sends Ctrl-C or SIGQUIT to an odohil process would see it
ignored: an odohil started so ignores them too, as any Unix tool does."""


def pytest_configure(config: pytest.Config) -> None:
    """Give the test processes the default dispositions of the signals the
    signal tests send, whatever the shell that started pytest left ignored."""
    for signum in _INHERITED_IGNORE:
        if signal.getsignal(signum) == signal.SIG_IGN:
            default = signal.default_int_handler if signum == signal.SIGINT else signal.SIG_DFL
            signal.signal(signum, default)
