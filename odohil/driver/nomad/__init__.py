"""The Nomad 150 backend over pyserial, in SI units.

``link`` (one request, one reply, Ndirect's timing), ``robot`` (the
``NomadRobot`` connection with SI methods), ``motion`` (forth-and-back runs),
``sample`` (the encoder reading in wire and SI units), ``backend``
(:class:`NomadBackend`, the session's ``Robot`` on a Nomad 150, registered as
``nomad150`` in the ``odohil.robots`` entry-point group).
"""
