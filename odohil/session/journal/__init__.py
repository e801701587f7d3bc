"""The record of a session: its typed events, the journal file, the state it replays to.

- events.py: the event dataclasses and their one JSON codec; ``FORMAT``, the
  record kinds' constants and ``OPERATOR``;
- file.py: :class:`Journal` (append-only, CRC-checked records), ``read_journal``;
- state.py: :class:`SessionState` and ``replay``.

Import from the modules; each module's ``__all__`` is its face.
"""

__all__ = [
    "events",
    "file",
    "state",
]
