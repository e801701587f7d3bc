"""odohil/session/plans/ (issue 32: the map follows)."""
