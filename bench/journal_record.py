"""What one journal record costs, and how much of it is holding the signals (issue 32).

Every record (odohil/session/journal/file.py ``Journal.append``) holds the
signals that end a session back while it is written and fsync-ed
(odohil/session/signals.py ``signals_deferred``). This appends ``--records``
small records (a measurement's size) to a fresh journal under each way odohil
sets the handlers up, and prints the CPU time per record (process time: the
machine is shared), the best of ``--repeat`` rounds:

- ``session``: ``odohil run`` and ``resume`` (``signals_raise`` and
  ``ctrl_c_in_words``: odohil's handlers on every held signal);
- ``wizard``: ``signals_raise`` only (Python's own Ctrl-C handler);
- ``none``: no session's handlers (a library caller, a test).

The folder is on ``/dev/shm`` where there is one (as in the test suite), so the
fsync costs next to nothing and the figure is the code's; on a disk each
fsync adds milliseconds. Run it at another commit with
``PYTHONPATH=<that checkout>`` for a before/after::

    python bench/journal_record.py [--records 2000] [--repeat 5]
"""

from __future__ import annotations

import argparse
import contextlib
import os
import sys
import tempfile
import time
from collections.abc import Callable, Iterator
from contextlib import AbstractContextManager
from pathlib import Path

if not os.environ.get("PYTHONPATH"):
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from odohil.session.journal.file import Journal
from odohil.session.signals import ctrl_c_in_words, signals_raise


@contextlib.contextmanager
def _session() -> Iterator[None]:
    with signals_raise(), ctrl_c_in_words():
        yield


SETTINGS: dict[str, Callable[[], AbstractContextManager[None]]] = {
    "session": _session,
    "wizard": signals_raise,
    "none": contextlib.nullcontext,
}


def per_record_us(setting: str, records: int, root: Path) -> float:
    """CPU microseconds per appended record under ``setting``."""
    with (
        tempfile.TemporaryDirectory(dir=root) as folder,
        SETTINGS[setting](),
        Journal.create(Path(folder) / "s") as journal,
    ):
        data = {"trial": 1, "attempt": 1, "value_m": 1.2345}
        started = time.process_time()
        for _ in range(records):
            journal.append("measurement", data)
        return (time.process_time() - started) / records * 1e6


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--records", type=int, default=2000)
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    shm = Path("/dev/shm")
    root = shm if shm.is_dir() and os.access(shm, os.W_OK) else Path(tempfile.gettempdir())
    print(f"load before: {os.getloadavg()[0]:.2f}; journals in {root}")
    print("| setting | CPU us per record (best of rounds) | rounds |")
    print("|---|---|---|")
    for setting in SETTINGS:
        best = min(per_record_us(setting, args.records, root) for _ in range(args.repeat))
        print(f"| {setting} | {best:.1f} | {args.repeat} x {args.records} |")
    print(f"load after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
