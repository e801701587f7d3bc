"""odohil/session/results/ (issue 32: the map follows)."""
