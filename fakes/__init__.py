"""Test doubles for odohil: a fake Nomad 150 robot that speaks the real serial protocol.

Importing this package registers the ``fakerobot://`` pyserial URL handler
(module :mod:`fakes.protocol_fakerobot`), so that
``serial.serial_for_url("fakerobot://?seed=1")`` opens an in-process fake robot.
"""

from __future__ import annotations

import serial

if "fakes" not in serial.protocol_handler_packages:
    serial.protocol_handler_packages.append("fakes")
