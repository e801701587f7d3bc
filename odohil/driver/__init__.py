"""The serial driver: one Nomad 150 over pyserial, in SI units.

``link`` (one request, one reply, Ndirect's timing), ``robot`` (the
``NomadRobot`` connection with SI methods), ``motion`` (forth-and-back runs).
"""
