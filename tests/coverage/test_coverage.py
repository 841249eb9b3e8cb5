"""Coverage of the stated uncertainty (issue 43): value ± U (k = 2) holds the generator's truth in
≥ 90 % of each kind × quantity, and U is no blanket (tests/coverage/campaign.py says how).

The whole campaign (≥ 300 records) runs under ``-m slow``: one test per cell of :data:`CELLS`,
the known defects of known_defects.py as ``xfail(strict=True)`` (a fix turns them red until its
line is removed). The default selection draws about 40 records with the scenario matrix's seed
(fixed per commit) and judges every cell it meets that is not a known defect; with so few
records per cell a share is judged by the binomial tail (the misses are too many for a 90 %
coverage at 1 % risk), not by the share alone; the blanket only on the whole campaign.
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import pytest

from . import campaign as cp
from .known_defects import BORDERLINE, KNOWN

# every cell the whole campaign judges (kind, quantity); a new cell is added here, judged from then on
CELLS = [
    ("CalculiX", "flow stress"), ("CalculiX", "friction_mu"), ("CalculiX", "johnson_cook A_MPa"),
    ("CalculiX", "johnson_cook B_MPa"), ("CalculiX", "johnson_cook n"),
    ("CalculiX zoned friction", "flow stress"), ("CalculiX zoned friction", "johnson_cook A_MPa"),
    ("CalculiX zoned friction", "johnson_cook B_MPa"), ("CalculiX zoned friction", "johnson_cook n"),
    ("compression closed form", "Rp02_MPa"), ("compression closed form", "flow stress"),
    ("compression closed form", "friction_mu"), ("compression closed form", "johnson_cook A_MPa"),
    ("compression closed form", "johnson_cook B_MPa"), ("compression closed form", "johnson_cook n"),
    ("tension crosshead", "E_MPa"), ("tension crosshead", "Ag_pct"), ("tension crosshead", "Rm_MPa"),
    ("tension crosshead", "Rp02_MPa"),
    ("tension drawn", "A_pct"), ("tension drawn", "Ag_pct"), ("tension drawn", "E_MPa"), ("tension drawn", "Rm_MPa"),
    ("tension drawn", "Rp02_MPa"), ("tension drawn", "johnson_cook A_MPa"), ("tension drawn", "johnson_cook B_MPa"),
    ("tension drawn", "johnson_cook n"),
    ("virtual rig", "E_MPa"), ("virtual rig", "Rm_MPa"), ("virtual rig", "Rp02_MPa"), ("virtual rig", "flow stress"),
    ("virtual rig", "friction_mu"), ("virtual rig", "johnson_cook A_MPa"), ("virtual rig", "johnson_cook B_MPa"),
    ("virtual rig", "johnson_cook n"),
]


def _param(cell):
    marks = [pytest.mark.xfail(strict=cell not in BORDERLINE, reason=KNOWN[cell])] if cell in KNOWN else []
    return pytest.param(cell, id=f"{cell[0]}|{cell[1]}", marks=marks)


@pytest.fixture(scope="module")
def whole():
    cases = cp.all_cases(cp.FALLBACK_SEED)
    rows, refused = cp.run_cases(cases)
    cells = {(c["kind"], c["quantity"]): c for c in cp.table(rows)}
    out = os.environ.get("FLOWCURVE_COVERAGE_TABLE")
    if out:  # the table for docs/test-report.md
        Path(out).write_text(cp.markdown(list(cells.values())) + "\n")
    return cases, cells, refused


@pytest.mark.slow
def test_the_campaign_is_whole(whole):
    """≥ 300 records, every kind present, and every cell it judges listed in CELLS (none left unjudged)."""
    cases, cells, _ = whole
    assert len(cases) >= 300
    assert {c.kind for c in cases} == {"tension drawn", "tension crosshead", "compression closed form", "CalculiX", "CalculiX zoned friction",
                                       "virtual rig"}
    assert sorted(cells) == sorted(CELLS), set(cells) ^ set(CELLS)


@pytest.mark.slow
@pytest.mark.parametrize("cell", [_param(c) for c in CELLS])
def test_cell_holds_the_truth(whole, cell):
    c = whole[1][cell]
    assert c["ok"], cp.markdown([c])


def too_many_misses(n: int, misses: int, coverage: float = cp.MIN_SHARE, risk: float = 0.01) -> bool:
    """P(X ≥ misses) < risk for X ~ Binomial(n, 1 − coverage): more misses than a 90 % coverage gives by chance."""
    p = 1.0 - coverage
    tail = sum(math.comb(n, k) * p**k * (1 - p) ** (n - k) for k in range(misses, n + 1))
    return tail < risk


SEED = cp.campaign_seed()



@pytest.fixture(scope="module")
def default_rows():
    cases = cp.default_cases(SEED)
    rows, refused = cp.run_cases(cases)
    return cases, rows, refused


def test_default_selection_holds_the_truth(default_rows):
    """About 40 records of every kind: each cell that is not a known defect holds the truth (binomial
    tail at 1 %). The blanket is judged on the whole campaign only: a median over ~10 mixed records
    scatters (the campaign's tension drawn E at 3.1× reads 5.3×, 5.6× and 26× on draws of 10)."""
    cases, rows, _ = default_rows
    assert 35 <= len(cases) <= 45 and {c.kind for c in cases} >= {"tension drawn", "compression closed form", "CalculiX", "virtual rig"}
    bad = []
    for c in cp.table(rows):
        cell = (c["kind"], c["quantity"])
        if cell in KNOWN:
            continue
        misses = round(c["n"] * (1 - c["share"]))
        if too_many_misses(c["n"], misses):
            bad.append(cp.markdown([c]).splitlines()[-1])
    assert not bad, f"seed {SEED} (FLOWCURVE_MATRIX_SEED={SEED} draws it again):\n" + "\n".join(bad)


def test_the_judge_bites(default_rows):
    """The same statements with U shrunk 20× miss; with U grown 50× they are a blanket: the judge can fail."""
    _, rows, _ = default_rows
    perfect = [r for r in rows if r["kind"] in cp.PERFECT and r["error"] > 0]
    assert perfect
    shrunk = [r | {"U": r["U"] / 20, "held": r["error"] <= r["U"] / 20} for r in perfect]
    grown = [r | {"U": r["U"] * 50, "held": True} for r in perfect]
    assert not all(c["ok"] for c in cp.table(shrunk))
    assert any(c["blanket"] for c in cp.table(grown))


def test_the_fe_model_form_is_a_condition_only_where_the_records_follow_the_products_friction_model():
    """"method: FE model form" leaves the method share on the closed-form and virtual-rig compression (their friction is
    the product's CalculiX runs') and stays in it on the CalculiX kind (the second model realises it)."""
    budget = {"k": 2.0, "components": [{"name": "fit (standard error)", "contribution": 3.0},
                                       {"name": "method: FE model form (1.3% of the force at μ 0.108, uniform and growing with strain)",
                                        "contribution": 4.0},
                                       {"name": "stress scale (force class, d0)", "contribution": 12.0}]}
    assert cp.method_share_U(budget, "compression closed form") == pytest.approx(6.0)
    assert cp.method_share_U(budget, "virtual rig") == pytest.approx(6.0)
    assert cp.method_share_U(budget, "CalculiX") == pytest.approx(10.0)


def test_too_many_misses():
    """Binomial tail against hand values: 0 of 5 is fine; 3 of 10 at 10 % has P = 0.0702; 4 of 10, P = 0.0128; 5 of 10, P = 0.00163."""
    assert not too_many_misses(5, 0)
    assert not too_many_misses(10, 4)
    assert too_many_misses(10, 5)
