"""odohil: calibrate the odometry error of a synchronous-drive mobile robot.

Layers, each importing only those below it:
science -> protocol -> driver -> session -> cli.
"""

__version__ = "0.1.0"
