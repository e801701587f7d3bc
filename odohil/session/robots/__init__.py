"""The robot seam: the ``Robot`` protocol the session drives, and the backends by name.

- protocol.py: :class:`Robot`, ``SampleCallback``: what a connected robot does;
- registry.py: the ``odohil.robots`` entry-point group: each backend's facts,
  its fake and emulator (plumbing: odohil/session/plugins.py);
- description.py: the robot description, from a file or a built-in name;
- line.py: which robot, port and baud a session uses, and the fake's truth channel.
"""

from odohil.session.robots.description import (
    builtin_names,
    load_robot_description,
    read_robot_toml,
    resolve_robot,
    robot_protocol,
)
from odohil.session.robots.line import Line, open_truth_client, resolve_line, truth_available
from odohil.session.robots.protocol import Robot, SampleCallback
from odohil.session.robots.registry import (
    RobotBackend,
    backend_names,
    check_baud,
    check_leg,
    emulate_help,
    emulated_line,
    emulator,
    fake_hooks,
    fake_url_schemes,
    find_backend,
    open_robot,
    parse_description,
    robot_facts,
)

__all__ = [
    "Line",
    "Robot",
    "RobotBackend",
    "SampleCallback",
    "backend_names",
    "builtin_names",
    "check_baud",
    "check_leg",
    "emulate_help",
    "emulated_line",
    "emulator",
    "fake_hooks",
    "fake_url_schemes",
    "find_backend",
    "load_robot_description",
    "open_robot",
    "open_truth_client",
    "parse_description",
    "read_robot_toml",
    "resolve_line",
    "resolve_robot",
    "robot_facts",
    "robot_protocol",
    "truth_available",
]
