"""The Nomad 150/200 direct serial protocol, bytes in and typed messages out.

No I/O here: ``numbers`` (wire integers), ``codes`` (command codes),
``framing`` (packets and a resynchronising stream decoder), ``messages``
(host requests), ``state`` (the state packet), ``replies`` (robot replies).
Every value is in WIRE units: 0.1 inch, 0.1 degree and their rates.
The protocol as odohil implements it is described in protocols/nomad/README.md.
"""
