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

``-n auto`` starts :data:`WORKERS_PER_CPU` workers a CPU: about 40 % of the
suite's wall time is spent waiting on the wall clock (robots driven at time
scale 1, motion-capture still windows, replies over real pseudo-terminals,
processes starting), which one worker a CPU leaves idle (docs/ci-time.md,
"Fifth round"). ``PYTEST_XDIST_AUTO_NUM_WORKERS`` still overrides it. The
tests listed in tests/slow_first.txt are handed out first, longest first.
"""

from __future__ import annotations

import os
import signal
from pathlib import Path
from typing import Any

import pytest
import typer.main
import typer.testing

from fakes.nomad.process import set_launcher
from tests.forked import start_fake

WORKERS_PER_CPU = 2
"""xdist workers a CPU under ``-n auto`` (module docstring)."""
SLOW_FIRST = Path(__file__).with_name("slow_first.txt")
"""Node ids (without parameters) of the longest tests, longest first."""

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
    chosen; restore the default dispositions of :data:`_INHERITED_IGNORE`;
    fork the fake robots from tests/forked.py's server."""
    set_launcher(start_fake)
    for signum in _INHERITED_IGNORE:
        if signal.getsignal(signum) == signal.SIG_IGN:
            default = signal.default_int_handler if signum == signal.SIGINT else signal.SIG_DFL
            signal.signal(signum, default)
    if getattr(config.option, "maxschedchunk", 0) is None:
        config.option.maxschedchunk = 1  # see pytest_collection_modifyitems
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


@pytest.hookimpl(optionalhook=True)  # an unknown hook without xdist (-p no:xdist)
def pytest_xdist_auto_num_workers(config: pytest.Config) -> int | None:
    """:data:`WORKERS_PER_CPU` workers per usable CPU, unless the environment
    names the number (xdist's own ``PYTEST_XDIST_AUTO_NUM_WORKERS``)."""
    if os.environ.get("PYTEST_XDIST_AUTO_NUM_WORKERS"):
        return None  # xdist's own implementation reads it
    affinity = getattr(os, "sched_getaffinity", None)  # Linux; elsewhere every CPU
    cpus = len(affinity(0)) if affinity is not None else (os.cpu_count() or 1)
    return WORKERS_PER_CPU * max(1, cpus)


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """The tests of :data:`SLOW_FIRST` first, in its order; the rest as collected.

    xdist's load scheduling would hand each worker a consecutive quarter of
    its share at the start (one worker all the long tests); pytest_configure
    sets ``--maxschedchunk=1`` unless given, so each free worker takes the next
    test."""
    names = [
        line.strip()
        for line in SLOW_FIRST.read_text(encoding="utf-8").splitlines()
        if line.strip() and not line.startswith("#")
    ]
    rank = {name: i for i, name in enumerate(names)}
    items.sort(key=lambda item: rank.get(item.nodeid.split("[", 1)[0], len(rank)))


_KEPT_DISPOSITIONS = (
    signal.SIGINT, signal.SIGTERM, signal.SIGHUP, signal.SIGQUIT, signal.SIGPIPE,
    signal.SIGUSR1, signal.SIGUSR2, signal.SIGTSTP, signal.SIGALRM,
)  # fmt: skip
"""Signals whose handler a test must leave as it found it: a worker left with
SIGINT's default action (not Python's Ctrl-C) is killed by the next test that
sends it, and xdist reports only "node down"."""


@pytest.fixture(autouse=True)
def _signal_dispositions_kept() -> Any:
    """Every test leaves the handlers of :data:`_KEPT_DISPOSITIONS` as it found
    them; one that does not is named, and the handlers are put back."""
    before = {signum: signal.getsignal(signum) for signum in _KEPT_DISPOSITIONS}
    yield
    changed = {s: h for s, h in before.items() if signal.getsignal(s) != h}
    for signum, handler in changed.items():
        signal.signal(signum, handler)  # type: ignore[arg-type]
    assert not changed, "left swapped: " + ", ".join(
        f"{signal.Signals(s).name} (found {h!r})" for s, h in changed.items()
    )
