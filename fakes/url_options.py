"""The fakes' URL options, read one by one: each bad one is a
:class:`~odohil.errors.PortOptionError` naming the option and what it takes,
which pyserial passes through ``serial_for_url`` and odohil's port opening
keeps (bad input: exit 2)."""

from __future__ import annotations

from odohil.errors import PortOptionError


def integer(key: str, value: str) -> int:
    """``value`` of option ``key`` as an integer."""
    try:
        return int(value)
    except ValueError:
        raise PortOptionError(f"{key} must be an integer, got {value!r}") from None


def number(key: str, value: str) -> float:
    """``value`` of option ``key`` as a number."""
    try:
        return float(value)
    except ValueError:
        raise PortOptionError(f"{key} must be a number, got {value!r}") from None


def unknown(key: str, accepted: tuple[str, ...]) -> PortOptionError:
    """The error for option ``key``, which is none of ``accepted``."""
    return PortOptionError(f"unknown option {key!r}; accepted: {', '.join(accepted)}")


def bad_url(scheme: str, url: str, exc: Exception) -> PortOptionError:
    """The error for a URL of ``scheme`` whose options are refused (``exc`` says why)."""
    return PortOptionError(f"bad {scheme} URL {url!r}: {exc}")
