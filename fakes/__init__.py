"""Test doubles for odohil: a fake Nomad 150 robot that speaks the real serial protocol.

:func:`register_url_handlers` (called on import too, for tests and scripts)
registers the ``fakerobot://`` pyserial URL handler (module
:mod:`fakes.protocol_fakerobot`), so that
``serial.serial_for_url("fakerobot://?seed=1")`` opens an in-process fake
robot. odohil's commands call it only for a ``fakerobot://`` port.
"""

from __future__ import annotations

import serial


def register_url_handlers() -> None:
    """Let ``serial.serial_for_url`` open the fakes' URL schemes (idempotent)."""
    if "fakes" not in serial.protocol_handler_packages:
        serial.protocol_handler_packages.append("fakes")


register_url_handlers()
