"""odohil/session/journal/ (issue 32: the map follows)."""
