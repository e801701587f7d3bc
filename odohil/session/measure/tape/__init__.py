"""The tape with the floor-marks solver.

- source.py: :class:`TapeSource`, the pose source over the tape's distances;
- distances.py: where the distances come from (the operator, the fake's
  truth, a recording);
- records.py: the tape's own journal events and its context.

Import from the modules; each module's ``__all__`` is its face.
"""

__all__ = [
    "distances",
    "records",
    "source",
]
