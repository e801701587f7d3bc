"""The verdict line, odohil/session/outcome_text.py's; kept here for
odohil/cli/validate.py, which imports it from this module."""

from odohil.session.outcome_text import outcome_line

__all__ = ["outcome_line"]
