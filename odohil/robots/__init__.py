"""The built-in robot descriptions (package data, one TOML file per robot).

``--robot NAME`` on the command line takes one of these when NAME is not a
file (odohil/cli/options.py); docs/measurements.md (screws, cross
distances, tape) and docs/create2.md (the Create 2's ``[robot]`` constants)
explain their values.
"""
