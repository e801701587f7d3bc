"""odohil/session/trials/ (issue 32: the map follows)."""
