"""The one session lifecycle every command uses (issue 18).

    spec = SessionSpec(folder, robot_path=..., plan=..., measure=..., port=...)
    checked = preflight(spec)           # the ordered checks; nothing written or moved
    prepared = require(checked)         # or PreflightFailed(first failure)
    with open_session(prepared) as opened:   # lock, connect, create or resume
        outcome = run_session(opened, observer)   # RunOutcome: status, stop, estimate

spec.py (what the user gave), checks.py (pre-flight), measure.py (the seam to
the pose sources), opening.py (open and connect), running.py (run to an
outcome). The CLI parses options into a :class:`SessionSpec`, passes its
observer (progress bar, wizard screens) and renders the outcome; the exit
status is odohil/cli/exit_codes.py's.
"""

from odohil.session.run.checks import (
    Preflight,
    PreflightCheck,
    PreflightFailed,
    Prepared,
    preflight,
    require,
)
from odohil.session.run.engine import SessionEngine, StartCheck
from odohil.session.run.opening import CheckSeen, Opened, connect, open_session
from odohil.session.run.running import (
    RunOutcome,
    final_estimate,
    interrupt_text,
    interrupted_before_run,
    progress_estimator,
    refused_before_run,
    run_session,
)
from odohil.session.run.spec import SessionSpec, default_session_folder
from odohil.session.run.start_pose import (
    HEADING_TOLERANCE_DEG,
    HERE,
    POSITION_TOLERANCE_M,
    StartPose,
    put_back,
    refuse_off_start,
)

__all__ = [
    "HEADING_TOLERANCE_DEG",
    "HERE",
    "POSITION_TOLERANCE_M",
    "CheckSeen",
    "Opened",
    "Preflight",
    "PreflightCheck",
    "PreflightFailed",
    "Prepared",
    "RunOutcome",
    "SessionEngine",
    "SessionSpec",
    "StartCheck",
    "StartPose",
    "connect",
    "default_session_folder",
    "final_estimate",
    "interrupt_text",
    "interrupted_before_run",
    "open_session",
    "preflight",
    "progress_estimator",
    "put_back",
    "refuse_off_start",
    "refused_before_run",
    "require",
    "run_session",
]
