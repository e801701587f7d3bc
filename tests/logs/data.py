"""Where the tests find the optiodom data set (../shared/data/optiodom-june
beside the repository, or $ODOHIL_OPTIODOM) and the description of its robot.
Outside CI the real-data tests skip without it; under CI (``CI`` set) its
absence is an error, so that the checks against real data cannot vanish."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from odohil.science.robot_description import RobotDescription
from odohil.session.robots.description import load_robot_description

ROOT = Path(__file__).resolve().parents[2]
OPTIODOM = Path(os.environ.get("ODOHIL_OPTIODOM", ROOT.parent / "shared/data/optiodom-june"))
OPTIODOM_ROBOT = ROOT / "docs/examples/optiodom.toml"

MISSING = f"the optiodom data set is not at {OPTIODOM} (set ODOHIL_OPTIODOM)"

if os.environ.get("CI") and not (OPTIODOM / "README.md").is_file():
    # CI has shared/ beside the clone: the real-data checks must run there, never skip
    raise RuntimeError(MISSING)

needs_optiodom = pytest.mark.skipif(not (OPTIODOM / "README.md").is_file(), reason=MISSING)


def optiodom_robot() -> RobotDescription:
    """The optiodom robot's description (docs/examples/optiodom.toml)."""
    return load_robot_description(OPTIODOM_ROBOT)
