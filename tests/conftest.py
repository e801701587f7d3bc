"""Suite-wide settings.

Test folders on a RAM file system where there is one: session tests write
journals, and the journal fsyncs every record (404 fsyncs in a 40-trial run:
4.5 s on a disk, nothing on tmpfs). So, unless the caller chose
(``--basetemp`` or ``PYTEST_DEBUG_TEMPROOT``), pytest's numbered
``pytest-of-<user>/pytest-N`` folders go under ``/dev/shm`` when it is a
writable folder with room; otherwise under the system's temporary folder as
usual. pytest's own numbering and locks keep concurrent runs (and xdist's
workers, which get folders under the controller's) apart, as they do in /tmp.
The journal's fsync calls still run: only where the bytes land changes.

The signals the signal tests send get their default dispositions, whatever
the shell that started pytest left ignored.

typer's test runner builds the click command of the whole ``odohil`` app
again on every ``invoke`` (every command's signature and help read anew:
60 ms of CPU on a loaded machine, more than a parse error's whole run).
:func:`_cached_get_command` builds it once per app and set of registered
commands; each invocation still gets a fresh click context, as the console
script does once per process.
"""

from __future__ import annotations

import os
import signal
from typing import Any

import pytest
import typer.main
import typer.testing

RAM_ROOT = "/dev/shm"
"""Where test folders go when it is usable (Linux's tmpfs)."""
MIN_FREE_BYTES = 1 << 30
"""Room the RAM file system must have left for the suite's folders, bytes."""


def _usable(root: str) -> bool:
    try:
        if not (os.path.isdir(root) and os.access(root, os.W_OK | os.X_OK)):
            return False
        stat = os.statvfs(root)
    except OSError:
        return False
    return stat.f_bavail * stat.f_frsize >= MIN_FREE_BYTES


_INHERITED_IGNORE = (signal.SIGINT, signal.SIGQUIT, signal.SIGHUP)
"""Signals a shell leaves ignored for a job it starts in the background (and
nohup for SIGHUP). Ignored dispositions pass to every process the tests start,
so a test that sends Ctrl-C or SIGQUIT to an odohil process would see it
ignored: an odohil started so ignores them too, as any Unix tool does."""


def pytest_configure(config: pytest.Config) -> None:
    """Point pytest's temporary root at :data:`RAM_ROOT` when nothing else was
    chosen; restore the default dispositions of :data:`_INHERITED_IGNORE`."""
    for signum in _INHERITED_IGNORE:
        if signal.getsignal(signum) == signal.SIG_IGN:
            default = signal.default_int_handler if signum == signal.SIGINT else signal.SIG_DFL
            signal.signal(signum, default)
    if config.option.basetemp or os.environ.get("PYTEST_DEBUG_TEMPROOT"):
        return
    if _usable(RAM_ROOT):
        os.environ["PYTEST_DEBUG_TEMPROOT"] = RAM_ROOT


_COMMANDS: dict[tuple[int, int, int, int], Any] = {}
_BUILD = typer.main.get_command


def _cached_get_command(typer_instance: typer.Typer) -> Any:
    """typer's ``get_command``, built once per app and registration state."""
    key = (
        id(typer_instance),
        len(typer_instance.registered_commands),
        len(typer_instance.registered_groups),
        id(typer_instance.registered_callback),
    )
    command = _COMMANDS.get(key)
    if command is None:
        command = _COMMANDS[key] = _BUILD(typer_instance)
    return command


if hasattr(typer.testing, "_get_command"):  # the runner's only use of it
    typer.testing._get_command = _cached_get_command
