"""The built-in robot descriptions (package data, one TOML file per robot).

``--robot NAME`` on the command line takes one of these when NAME is not a
file (odohil/cli/robot_option.py); docs/create2.md and docs/robot-description.md
explain their values.
"""
