"""A fake iRobot Create 2 that speaks the Open Interface (OI) on a pty.

``python -m fakes.create2`` or ``odohil emulate --robot create2``; in process
as ``fakecreate2://`` (:mod:`fakes.protocol_fakecreate2`). See docs/create2.md.
"""
