"""Slow CalculiX checks: the table regenerates, and the default compression method reads FE
records the table did not train on (other μ, h0/d0, d0 and hardening laws, with encoder
steps, noise and frame compliance) to within 2 % over ε_p 0.05–0.6 and μ ± 0.02.

Known limits, measured (bench/fe_methods.py) and kept here as strict expected failures so a
fix shows up: the table's single hardening exponent n does not carry the barrel of a law with
a high yield plateau (steel 45, A 410 B 280: μ read 0.30 for 0.25) or a saturating Voce law
(μ 0.27 for 0.17); at μ 0.28 on the seed's law μ is right but the curve is 3.2 % off. A seating toe of 0.03 mm costs another 1.5–3 % at ε_p = 0.05 until the
compression identification compensates the toe (the records here have none)."""

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
    for mu, h0_d0, n in ((0.2, 1.0, 0.4), (0.05, 1.6, 0.2)):
        i, j, k = list(z["mu"]).index(mu), list(z["h0_d0"]).index(h0_d0), list(z["n"]).index(n)
        run = sample_run((mu, h0_d0, n))
        assert not run["cached"]
        np.testing.assert_allclose(run["factor_raw"], z["force_factor_raw"][i, j, k], rtol=1e-6)
        np.testing.assert_allclose(run["bulge"], z["bulge_dR_over_h"][i, j, k], rtol=1e-5, atol=1e-7)


LIMITS = {2: "high yield plateau: the table's n does not carry its barrel", 3: "saturating Voce law: the table's n does not carry its barrel",
          5: "μ 0.28 on the seed's strongly hardening law: μ right (0.269) but the flow curve 3.2 % off"}
CASES = [pytest.param(c, marks=pytest.mark.xfail(strict=True, reason=LIMITS[k])) if k in LIMITS else c for k, c in enumerate(VALIDATION_CASES)]


@pytest.mark.parametrize("case", CASES, ids=[c["name"] for c in VALIDATION_CASES])
def test_default_method_reads_fe_records(case):
    run = run_case(case)
    ident = identify_compression(upsetting_record(run, seed=3, toe_mm=0.0))
    assert ident.result["friction_method"] == "fe_table" and ident.result["friction_correction"] == "fe_table"
    assert ident.result["friction_mu"] == pytest.approx(case["mu"], abs=0.02)
    c = ident.true_curve
    e, s = c["true_plastic_strain"].to_numpy(), c["true_stress_MPa"].to_numpy()
    sel = (e >= 0.05) & (e <= 0.6)
    assert np.max(np.abs(s[sel] / case_flow(case)(e[sel]) - 1.0)) < 0.02
