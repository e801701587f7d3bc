"""``odohil demo`` for a newcomer (issue 11, item 6): the truth in the table, in
the chosen units, beside the estimate and its interval (before: a raw Python
dict on stderr); a re-measure by the simulated operator said in plain words
(before: "trial 29: distances rejected, taken again")."""

from __future__ import annotations

import re

import pytest

from odohil import units
from odohil.session.commands.demo import DEMO_TRUTH
from odohil.session.journal.file import read_journal
from odohil.session.measure.tape.records import MeasurementsRejected, Remeasured
from tests.demo_run import demo_run


def _row(table: str, name: str) -> list[str]:
    line = next(line for line in table.splitlines() if line.strip("│┃ ").startswith(name + " "))
    return [cell.strip() for cell in re.split("[│┃]", line.strip("│┃ "))]


@pytest.mark.slow
def test_demo_shows_the_truth_in_its_table_and_says_who_measured_again(
    tmp_path_factory: pytest.TempPathFactory,
) -> None:
    done, session = demo_run(tmp_path_factory)  # the run test_backward_prediction reads too
    assert done.returncode == 0, done.stderr
    header = _row(done.stdout, "parameter")
    assert header[-2:] == ["truth", "truth inside"]
    truth = DEMO_TRUTH.to_si_dict()
    for name, value in truth.items():
        row = _row(done.stdout, name)
        shown = units.parameter_in(name, value, "paper")
        assert float(row[header.index("truth")]) == pytest.approx(shown, rel=1e-3)
        assert row[header.index("unit")] == units.unit_column(name, "paper")
    assert "{'" not in done.stderr  # no raw dict
    assert "E_R = -1 deg/m, E_T = -0.05, K_theta = 0.3 deg^2/m" in " ".join(done.stderr.split())
    records = read_journal(session).records
    rejected = [r.data["trial"] for r in records if r.kind == MeasurementsRejected.KIND]
    remeasured = [r.data["trial"] for r in records if r.kind == Remeasured.KIND]
    assert rejected or remeasured, "the default seed has the simulated operator measure again"
    text = " ".join(done.stderr.split())
    assert "distances rejected" not in text
    for trial in rejected:
        assert f"trial {trial}: the distances the simulated operator took fit no rigid" in text
    if remeasured:
        assert "the simulated operator measured it again" in text
    for trial in dict.fromkeys(remeasured):
        assert f"{trial}" in text
