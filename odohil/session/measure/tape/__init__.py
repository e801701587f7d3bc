"""odohil/session/measure/tape/ (issue 32: the map follows)."""
