"""2 Hz load-cell delay cells whose gap the acquisition names in doubt or undecided (docs/methods.md, load-cell stream
gaps): each budget the gap's term widens holds the fault-free run's value within its U, and the term is the size of
the fault's own error (the realigned record is the fault-free one up to the frames' interpolation)."""

from __future__ import annotations

import dataclasses

import pytest

from flowcurve.identification.quality import stream_gap
from flowcurve.record.importers import load_record
from tests.scenarios.matrix import NO_FAULT, all_cells, run_cell

CELLS = ("tension-600C-0.005mmps-2Hz-12Kh18N12M3TL-loadcell:delay:0.5", "tension-850C-0.005mmps-2Hz-steel45-loadcell:delay:0.5")


def _budgets(unc: dict) -> dict:
    out = {k: unc[k] for k in ("Rp02_MPa", "Ag_pct", "Rm_MPa") if isinstance(unc.get(k), dict)}
    for block in ("hardening", "flow_stress_MPa"):
        out |= {f"{block} {k}": b for k, b in (unc.get(block) or {}).items() if isinstance(b, dict) and "value" in b}
    return out


@pytest.mark.slow
@pytest.mark.parametrize("cell_id", CELLS)
def test_the_fault_free_values_lie_within_the_gap_widened_U(cell_id, tmp_path):
    cell = {c.id: c for c in all_cells()}[cell_id]
    fault, free = run_cell(cell, tmp_path / "fault"), run_cell(dataclasses.replace(cell, fault=NO_FAULT), tmp_path / "free")
    if not stream_gap.gaps(load_record(fault.record_path)) or fault.result is None or free.result is None:
        pytest.skip("this run's gap was decided (the threads' timing) or a run did not identify")
    mine, truth = _budgets(fault.result["uncertainty"]), _budgets(free.result["uncertainty"])
    assert all(c["name"] != stream_gap.COMPONENT for c in mine["Rm_MPa"]["components"])
    widened = {k: b for k, b in mine.items() if any(c["name"] == stream_gap.COMPONENT for c in b.get("components", []))}
    assert "Rp02_MPa" in widened and "Ag_pct" in widened
    for key, b in widened.items():
        assert abs(b["value"] - truth[key]["value"]) <= b["U"], key
