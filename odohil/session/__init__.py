"""Layer 4: running a calibration session, by concept (docs/architecture.md).

From the bottom up, each subpackage imports only those below it
(tests/test_session_packages.py):

- robots/: the ``Robot`` protocol the session owns, and the backends by name;
- plans/: the plan and what it must satisfy before anything moves;
- trials/: trials from files (trial files, pose files, recorded logs);
- journal/: the session's record: typed events, the journal file, the replayed state;
- measure/: pose sources, the ``PoseSource`` protocol and ``--measure``'s registry;
- results/: the one recipe to an estimate, validation, exports, the report;
- run/: one session's lifecycle: pre-flight, opening, the engine, the start pose;
- text/: the words every command prints;
- commands/: what each command computes besides the above;
- wizard/: the operator at the robot.

The ground modules import nothing of the session: bounded_io.py (reads within
a size limit), signals.py (signals as exceptions), table_text.py, plugins.py
(plug-ins by name), addresses.py (the addresses a header journals) and
progress.py (how far reading and fitting have gone; the terminal's bar).
"""
