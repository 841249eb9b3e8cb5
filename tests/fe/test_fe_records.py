"""Slow CalculiX checks: the table regenerates, and the default compression method reads FE
records the table did not train on (other μ, h0/d0, d0 and hardening laws, with encoder
steps, noise and frame compliance) to within 2 % over ε_p 0.05–0.6 and μ ± 0.02.

The records are made with a finer mesh (30 core elements, a d0/30 rim layer; 24 for the one
case the finer mesh cannot finish) than the table's, 70 increments and a resolved elastic line.
Known limits, measured and kept here as strict expected failures so a fix shows up: where the
barrel hardly grows with μ (near sticking) one 0.01 mm of dmax moves μ by 0.05–0.12, and on tall
specimens at μ ≥ 0.15 the table's runs stop at ε 0.3–0.6 (the side folds onto the platen) and
are continued along the next lower μ. Each such record carries an FE-table warning: a miss
never leaves without one (test_a_record_the_default_misses_is_flagged)."""

from __future__ import annotations

import shutil

import numpy as np
import pytest

from flowcurve.identification.compression import identify_compression
from flowcurve.identification.fe.synthetic import VALIDATION_CASES, case_flow, run_case, upsetting_record

pytestmark = [pytest.mark.slow, pytest.mark.solver, pytest.mark.skipif(shutil.which("ccx") is None, reason="CalculiX (ccx) is not installed")]


def test_table_points_regenerate_with_ccx(tmp_path, monkeypatch):
    """Two of the shipped table's runs, run again (no cache), give the same numbers."""
    from flowcurve.identification.fe.make_table import sample_run
    from flowcurve.identification.fe.table import PACKAGE_TABLE

    monkeypatch.setenv("FLOWCURVE_FE_CACHE", str(tmp_path))
    z = np.load(PACKAGE_TABLE)
    for mu, h0_d0, n, eps0 in ((0.2, 1.0, 0.4, 0.02), (0.05, 1.6, 0.2, 0.1)):
        i, j, k, m = (list(z[axis]).index(v) for axis, v in (("mu", mu), ("h0_d0", h0_d0), ("n", n), ("eps0", eps0)))
        run = sample_run((mu, h0_d0, n, eps0))
        assert not run["cached"]
        np.testing.assert_allclose(run["factor_raw"], z["force_factor_raw"][i, j, k, m], rtol=1e-6)
        np.testing.assert_allclose(run["bulge"], z["bulge_dR_over_h"][i, j, k, m], rtol=1e-5, atol=1e-7)


LIMITS = {2: "steel 45 at μ 0.25, h0/d0 1: the barrel hardly grows with μ there (one 0.01 mm of dmax moves μ by 0.05): μ read 0.285, "
             "flagged; the curve within 1.9 %",
          3: "Voce at μ 0.17, h0/d0 1.8: the table's runs at μ ≥ 0.15 stop at ε 0.38–0.47 on tall specimens (continued, flagged): "
             "μ 0.27, the curve 2.1 % off",
          5: "seed law at μ 0.28, h0/d0 1.2: runs continued beyond ε 0.32 and a barrel flat in μ (flagged): μ 0.345, the curve 3.1 % off"}
CASES = [pytest.param(c, marks=pytest.mark.xfail(strict=True, reason=LIMITS[k])) if k in LIMITS else c for k, c in enumerate(VALIDATION_CASES)]


def _read(case):
    ident = identify_compression(upsetting_record(run_case(case), seed=3, toe_mm=0.0))
    c = ident.true_curve
    e, s = c["true_plastic_strain"].to_numpy(), c["true_stress_MPa"].to_numpy()
    sel = (e >= 0.05) & (e <= 0.6)
    return ident, float(np.max(np.abs(s[sel] / case_flow(case)(e[sel]) - 1.0)))


@pytest.mark.parametrize("case", CASES, ids=[c["name"] for c in VALIDATION_CASES])
def test_default_method_reads_fe_records(case):
    ident, err = _read(case)
    assert ident.result["friction_method"] == "fe_table" and ident.result["friction_correction"] == "fe_table"
    assert ident.result["friction_mu"] == pytest.approx(case["mu"], abs=0.02)
    assert err < 0.02


@pytest.mark.parametrize("case", VALIDATION_CASES, ids=[c["name"] for c in VALIDATION_CASES])
def test_a_record_the_default_misses_is_flagged(case):
    """Never a miss without a word: μ off by more than 0.02 or the curve by more than 2 % comes
    with an FE-table warning in the result (and on the screen)."""
    ident, err = _read(case)
    missed = abs(ident.result["friction_mu"] - case["mu"]) > 0.02 or err > 0.02
    flagged = [w for w in ident.result["warnings"] if w.startswith("FE table:")]
    if missed:
        assert flagged, (ident.result["friction_mu"], err)
