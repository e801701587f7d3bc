"""odohil/session/measure/ (issue 32: the map follows)."""
