"""Layer 4: trials, journal, live estimates, and the two protocols the session
owns: ``Robot`` (robot.py, backends by name in robots.py) and ``PoseSource``
(pose_source.py, sources in sources.py)."""
