"""What each command computes, one module per command (beside odohil/cli/<name>.py).

- plan.py and plan_paths.py: ``odohil plan`` (designs; general paths);
- design.py: ``odohil predict``, ``covariance`` and ``simulate``; design_tables.py:
  their tables (a module of its own: the captions' words load the estimate's);
- validate.py: ``odohil validate``; validate_power.py: its ``--detect`` (the
  trials that catch an error); demo.py: ``odohil demo``;
- report.py: ``odohil report``; import_log.py: ``odohil import``.

Only what no other subpackage owns is here. The CLI imports the module named
after its command; each module's ``__all__`` is its face.
"""

__all__ = [
    "demo",
    "design",
    "design_tables",
    "import_log",
    "plan",
    "plan_paths",
    "report",
    "validate",
    "validate_power",
]
