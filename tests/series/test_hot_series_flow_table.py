"""Issue 45's must-show end to end on records: the held-out hot series (tests/series/hot_series.py,
700/800/900 °C × 0.001/0.01/0.1 1/s, constant true strain rate, 50 Hz, E given) through
`flowcurve fit --law hensel_spittel` and `flowcurve card --format flow-table`: the table's stress at
each of the nine measured conditions within 3 % of the generating law over εp 0.05–0.6.
Slow: the 0.001 1/s records are 35 000 samples each (about 20 s for the fit)."""

import csv

import numpy as np
import pytest

from flowcurve.cli import main
from flowcurve.record.format import write_record

from .hot_series import E_MPa, SERIES, flow, hot_record


@pytest.mark.slow
def test_flow_table_of_a_hensel_spittel_fit_holds_the_true_law_at_the_nine_conditions(tmp_path):
    paths = [str(write_record(tmp_path / f"{rec.source}.csv", rec)) for rec in (hot_record(T, r)[0] for T, r in SERIES)]
    assert main(["fit", *paths, "--law", "hensel_spittel", "--E", repr(E_MPa), "--out", str(tmp_path / "fit")]) == 0
    table = tmp_path / "table.csv"
    assert main(["card", str(tmp_path / "fit" / "fit.json"), "-f", "flow-table", "-o", str(table)]) == 0
    with open(table, encoding="utf-8") as fh:
        rows = list(csv.reader(line for line in fh if not line.startswith("#")))
    assert rows[0] == ["eps_p", "strain_rate_per_s", "temperature_C", "stress_MPa"]
    grid = np.array([[float(v) for v in row] for row in rows[1:]])
    for T, rate in SERIES:
        at = (np.abs(grid[:, 2] - T) < 0.5) & (np.abs(grid[:, 1] / rate - 1.0) < 0.01) & (grid[:, 0] >= 0.05) & (grid[:, 0] <= 0.6)
        assert at.sum() >= 10, (T, rate)  # the condition is in the table, over the whole range
        deviation = grid[at, 3] / flow(grid[at, 0], rate, T) - 1.0
        assert np.max(np.abs(deviation)) < 0.03, (T, rate, float(np.max(np.abs(deviation))))
