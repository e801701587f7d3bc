"""odohil/session/robots/ (issue 32: the map follows)."""
