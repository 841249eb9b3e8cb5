"""Compression Rp0.2 with a toe on coarse records: the toe's end, the few samples of the elastic
line and the yield all within a handful of samples.

Forward model of toe_records.py (independent of the identification): a seating toe of 0.02 or
0.05 mm that closes only at 1500 N (53 MPa, half the yield stress), sampled at 1–3 Hz, handbook E
in the record. The old code regressed a "line" over the toe and the plastic start there (E_line
2–5 GPa) and placed the toe at 0.2–0.7 mm: Rp0.2 +81 %, +246 %, +265 % without a warning.
A CalculiX record (slow) checks the same against the solver: the seed law at μ 0.15, toe 0.02 mm,
10 Hz, Rp0.2 within 5 % of the mean pressure at εp 0.002.
"""

from __future__ import annotations

import math
import shutil

import numpy as np
import pytest

from flowcurve.identification.compression.identify import identify_compression, toe_on_flattest_offsets

from .toe_records import make_toe_compression


@pytest.mark.parametrize("toe_mm", [0.02, 0.05])
@pytest.mark.parametrize("rate_hz", [1.0, 2.0, 3.0])
def test_rp02_with_a_long_toe_on_few_samples(toe_mm, rate_hz):
    for seed in (1, 2, 3):
        rec, truth = make_toe_compression(toe_mm=toe_mm, rate_hz=rate_hz, handbook_E=True, seed=seed, toe_force_N=1500.0)
        res = identify_compression(rec).result
        assert res["Rp02_MPa"] == pytest.approx(truth["rp02_pressure_MPa"], rel=0.05), (seed, res["warnings"])
        assert res["indicator"]["toe_compensation_mm"] == pytest.approx(toe_mm, abs=0.005)
        assert not [w for w in res["warnings"] if w.startswith("no elastic line")]


def test_the_flattest_offsets_are_the_elastic_line():
    """Offsets Δl − h0·σ/E of a toe (growing), a line (constant 0.05) and yield (growing again)."""
    h0, E, area = 7.0, 194_000.0, 28.0
    sigma = np.array([5, 15, 30, 45, 60, 75, 90, 110, 125, 140], dtype=float)
    offset = np.array([0.010, 0.025, 0.040, 0.0480, 0.0500, 0.0501, 0.0500, 0.056, 0.070, 0.090])
    disp = offset + h0 * sigma / E
    toe, window = toe_on_flattest_offsets(disp, sigma * area, E_MPa=E, area0_mm2=area, h0_mm=h0, upto_MPa=150.0)
    assert toe == pytest.approx(0.0500, abs=2e-4) and window == (60.0, 90.0)


@pytest.mark.slow
@pytest.mark.solver
@pytest.mark.skipif(shutil.which("ccx") is None, reason="CalculiX (ccx) is not installed")
def test_calculix_upsetting_record_with_a_toe():
    from flowcurve.identification.fe import synthetic as syn

    law = {"A": 105.0, "B": 1392.0, "n": 0.642}
    case = {"name": "seed law, mu 0.15", "law": (syn.johnson_cook_flow, law), "mu": 0.15, "d0": 6.0, "h0": 9.0, "eps_end": 0.72, "E": 194_000.0}
    run = syn.run_case(case)
    rec = syn.upsetting_record(run, toe_mm=0.02, rate_hz=10.0)
    res = identify_compression(rec).result
    # the flow stress at εp 0.002, and the mean pressure with Coulomb friction over the face (slab, r/h 1/3)
    flow = law["A"] + law["B"] * 0.002 ** law["n"]
    pressure = flow * (1.0 + 2.0 * 0.15 * (3.0 / 9.0) / 3.0)
    assert flow * 0.99 < res["Rp02_MPa"] < pressure * 1.05, res["Rp02_MPa"]
    assert res["indicator"]["toe_compensation_mm"] == pytest.approx(0.02, abs=0.003)
    assert not [w for w in res["warnings"] if w.startswith("no elastic line")]
    assert math.isfinite(res["E_MPa"])
