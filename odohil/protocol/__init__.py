"""Robot protocols: bytes in, typed messages out, one subpackage per protocol.

No I/O here. ``nomad`` is the Nomad 150/200 direct serial protocol
(protocols/nomad/README.md).
"""
