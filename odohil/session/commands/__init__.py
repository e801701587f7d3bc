"""odohil/session/commands/ (issue 32: the map follows)."""
