"""odohil/session/wizard/ (issue 32: the map follows)."""
