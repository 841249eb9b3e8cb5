"""The split of compression.py (issue 44) changes no number: result.json against a stored reference.

The reference (``data/identify_reference.json``) was written by the code of commit 01c1793, before
the split, with::

    git archive 01c1793 | tar -x -C /tmp/old
    FLOWCURVE_DEV_ROOT=/tmp/old python tests/compression/test_identify_numbers_unchanged.py --write

Rewritten since, each time for a change of the numbers that says why: the flow stress budgets state the fe_table
correction's own per-point σ (true_curve.csv correction_uncertainty_pct; docs/methods.md §4.8, issue 43): only
uncertainty.flow_stress_MPa's U, u, u_method and their new component moved.

Every leaf is compared as in tests/tension/test_identify_numbers_unchanged.py (numbers to a
relative 1e-9, everything else exactly).
"""

from __future__ import annotations

import importlib.util
import json
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
REFERENCE = Path(__file__).with_name("data") / "identify_reference.json"
RECORDS = {"compression-steel45": ROOT / "examples" / "data" / "compression-steel45.csv"}


def _tension_guard():
    spec = importlib.util.spec_from_file_location("tension_numbers_unchanged", ROOT / "tests" / "tension" / "test_identify_numbers_unchanged.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def result_of(case: str) -> dict:
    """result.json (as written) of one vendored compression record."""
    from flowcurve.identification.identify import identify
    from flowcurve.identification.outcome import to_jsonable
    from flowcurve.record.importers import load_record

    result = json.loads(json.dumps(to_jsonable(identify(load_record(RECORDS[case])).result), allow_nan=False))
    result["record"].pop("path")  # where the file lies, not a result
    return result


@pytest.mark.parametrize("case", sorted(RECORDS))
def test_result_json_unchanged(case):
    reference = json.loads(REFERENCE.read_text(encoding="utf-8"))
    assert reference[case]["test"] == "compression"
    diff = _tension_guard().differences(result_of(case), reference[case])
    assert not diff, f"{case}: {len(diff)} fields changed: " + "; ".join(diff[:10])


if __name__ == "__main__" and sys.argv[1:] == ["--write"]:
    out = {case: result_of(case) for case in RECORDS}
    REFERENCE.parent.mkdir(exist_ok=True)
    REFERENCE.write_text(json.dumps(out, indent=1, sort_keys=True) + "\n", encoding="utf-8")
    print(f"wrote {REFERENCE}")
