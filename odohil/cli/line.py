"""The fakes' pyserial URL handlers, registered from the CLI (the only layer
that may import the fakes); the line itself is resolved in the session layer
(odohil/session/line.py)."""

from __future__ import annotations

from odohil.session.line import Line, resolve_line
from odohil.session.robots import fake_url_schemes

__all__ = ["Line", "register_fake_urls", "resolve_line"]


def register_fake_urls(port: str) -> None:
    """Register the fakes' pyserial URL handlers when ``port`` uses one (and
    only then: no fake is imported otherwise)."""
    if port.startswith(fake_url_schemes()):
        import fakes

        fakes.register_url_handlers()
