"""odohil/session/text/ (issue 32: the map follows)."""
