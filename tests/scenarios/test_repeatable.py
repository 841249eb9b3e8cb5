"""Two in-process runs of the same cell on model time record the same samples from the start:
the reading threads' start does not race (a reader woken by its reply acts before time moves on)."""

import numpy as np

from flowcurve.record.format import read_record

from . import matrix

FIRST_ROWS = 50
CELL = "tension-20C-0.5mmps-50Hz-steel45-none"  # ~300 rows, about a second a run


def test_two_runs_of_one_cell_record_the_same_first_rows(tmp_path):
    cell = next(c for c in matrix.all_cells() if c.id == CELL)
    rows = []
    for k in range(2):
        run = matrix.run_cell(cell, tmp_path / str(k))
        assert run.run_code == 0, run.run_err
        rows.append(read_record(run.record_path).data.to_numpy()[:FIRST_ROWS])
    assert rows[0].shape == (FIRST_ROWS, 4)
    differ = np.flatnonzero(np.any(rows[0] != rows[1], axis=1))
    assert differ.size == 0, f"row {differ[0]} differs: {rows[0][differ[0]]} vs {rows[1][differ[0]]}"
