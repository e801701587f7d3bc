"""Robot drivers: one backend subpackage per robot protocol, each behind the
session's ``Robot`` protocol (odohil/session/robots/protocol.py).

Shared by every backend: ``port`` (a serial URL opened with
``serial.serial_for_url``, so a real port, ``socket://``, ``rfc2217://`` and
the fakes share one code path) and ``odometry`` (the robot-neutral SI values
a backend hands up). ``nomad`` drives a Nomad 150.
"""
