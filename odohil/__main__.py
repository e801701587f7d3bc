"""``python -m odohil`` runs the command-line interface."""

from odohil.cli.app import main

main()
