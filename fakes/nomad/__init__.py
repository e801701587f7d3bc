"""The fake Nomad 150 robot: engine, body physics, pty server, truth side channel.

- :class:`fakes.nomad.engine.NomadEngine`: the robot (bytes in, bytes out);
- :class:`fakes.nomad.process.EmulatorProcess`: run it as a pty subprocess;
- :class:`fakes.nomad.truth.TruthClient`: read its true pose;
- ``fakerobot://`` (:mod:`fakes.protocol_fakerobot`): the same robot in process.

See docs/fake-robot.md.
"""
