"""Fault injection: which request gets which misbehaviour.

Syntax of one fault: ``NAME[:CODE][@N]``

- ``NAME``: one of :data:`FAULT_NAMES`;
- ``CODE``: the command whose requests are affected, by name (``gs``,
  ``get_rc``, ``pr``...) or number; default: every request for the reply
  faults and ``noise``, the motion commands (pr, pa, vm, mv) for ``stuck``,
  ``disconnect`` and ``watchdog``;
- ``@N``: only the N-th matching request (1-based); default: every one.

What each fault does on the wire is documented in protocols/nomad/README.md
("Fault injection") and docs/fake-robot.md.
"""

from __future__ import annotations

from dataclasses import dataclass

from odohil.errors import ParameterError
from odohil.protocol.nomad.codes import Code

REPLY_FAULTS = (
    "corrupt", "drop", "late", "split", "merge", "garbage", "nak", "wrong-type", "stray",
)  # fmt: skip
MOTION_FAULTS = ("stuck", "disconnect", "watchdog")
LINE_FAULTS = ("noise",)
"""Faults that take the line over: from the request they hit on, no more replies."""
FAULT_NAMES = REPLY_FAULTS + MOTION_FAULTS + LINE_FAULTS
DEFAULT_MOTION_CODES = frozenset({Code.PR, Code.PA, Code.VM, Code.MV})


@dataclass(frozen=True)
class FaultSpec:
    """One fault: its name, the command code it hits (None: default set), which occurrence.

    Attributes:
        name: one of :data:`FAULT_NAMES`.
        code: command code, or None for the default set of the fault.
        nth: 1-based occurrence among matching requests, or None for every one.
    """

    name: str
    code: int | None = None
    nth: int | None = None

    def __post_init__(self) -> None:
        if self.name not in FAULT_NAMES:
            raise ParameterError(f"unknown fault {self.name!r}; known: {', '.join(FAULT_NAMES)}")
        if self.nth is not None and self.nth < 1:
            raise ParameterError(f"fault occurrence must be >= 1, got {self.nth}")

    def matches(self, code: int) -> bool:
        """Whether a request of ``code`` counts for this fault."""
        if self.code is not None:
            return code == self.code
        if self.name in MOTION_FAULTS:
            return code in DEFAULT_MOTION_CODES
        return True

    def __str__(self) -> str:
        text = self.name
        if self.code is not None:
            known = self.code in {c.value for c in Code}
            text += f":{Code(self.code).name.lower() if known else self.code}"
        if self.nth is not None:
            text += f"@{self.nth}"
        return text


def parse_fault(text: str) -> FaultSpec:
    """Parse ``NAME[:CODE][@N]`` (see the module docstring); ParameterError if malformed."""
    rest = text.strip()
    nth: int | None = None
    if "@" in rest:
        rest, _, count = rest.partition("@")
        try:
            nth = int(count)
        except ValueError:
            raise ParameterError(f"bad fault occurrence in {text!r}") from None
    code: int | None = None
    name, sep, code_text = rest.partition(":")
    if sep:
        code = _parse_code(code_text, text)
    return FaultSpec(name.strip().lower(), code, nth)


def _parse_code(code_text: str, text: str) -> int:
    key = code_text.strip()
    if key.isdigit():
        return int(key)
    try:
        return int(Code[key.upper()])
    except KeyError:
        raise ParameterError(f"unknown command {key!r} in fault {text!r}") from None


class FaultPlan:
    """Counts requests per fault and says which faults fire on each request."""

    def __init__(self, specs: tuple[FaultSpec, ...]) -> None:
        self.specs = specs
        self._counts = [0] * len(specs)

    def fire(self, code: int) -> frozenset[str]:
        """The names of the faults that hit this request of ``code`` (counts it)."""
        fired: set[str] = set()
        for index, spec in enumerate(self.specs):
            if not spec.matches(code):
                continue
            self._counts[index] += 1
            if spec.nth is None or spec.nth == self._counts[index]:
                fired.add(spec.name)
        return frozenset(fired)
