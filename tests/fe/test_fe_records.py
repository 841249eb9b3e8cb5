"""Slow CalculiX checks: the table regenerates, and the default compression method reads FE
records the table did not train on (other μ, h0/d0, d0 and hardening laws, with encoder
steps, noise and frame compliance) to within 2 % over ε_p 0.05–0.6 and μ ± 0.02.

The records are made with a finer mesh (30 core elements, a d0/30 rim layer; 24 for the one
case the finer mesh cannot finish) than the table's, 70 increments and a resolved elastic line.
The table's bulge is the one measured on the unloaded specimen (table.bulge_as_measured); read
under load and less the μ = 0 runs' rim-corner mesh bump, as it was, it read μ 0.03–0.04 high
near sticking (steel 45 0.288 for 0.25, the seed law 0.319 for 0.28).
Known limits, measured and kept here as strict expected failures so a fix shows up: where the
barrel hardly grows with μ (near sticking) one 0.01 mm of dmax moves μ by 0.03–0.1 (the reported
friction_mu_range then opens to the table's largest μ), and near sticking the force itself dips
by 1–2 % each time a node of the side folds onto the platen, at other strains in the record than
in the table's runs (which on h0/d0 ≥ 1.6 at μ ≥ 0.15 also stop at ε 0.27–0.9 and are continued
along the next lower μ). Each such record carries an FE-table warning: a miss never leaves
without one (test_a_record_the_default_misses_is_flagged)."""

from __future__ import annotations

import shutil

import numpy as np
import pytest

from flowcurve.identification.compression.identify import identify_compression
from flowcurve.identification.fe.synthetic import VALIDATION_CASES, case_flow, run_case, upsetting_record

pytestmark = [pytest.mark.slow, pytest.mark.solver, pytest.mark.skipif(shutil.which("ccx") is None, reason="CalculiX (ccx) is not installed")]


def test_table_points_regenerate_with_ccx(tmp_path, monkeypatch):
    """Three of the shipped table's runs, run again (no cache), give the same numbers."""
    from flowcurve.identification.fe.make_table import sample_run
    from flowcurve.identification.fe.model.table import PACKAGE_TABLE

    z = np.load(PACKAGE_TABLE)
    # the last stopped with stick slope 1e7 at ε 0.41 and is in the table from its retry (1e6). That run is
    # not bit-reproducible: of 7 fresh runs 5 gave the table's numbers exactly and 2 differed by up to 5.1e-5 in
    # the force factor at ε ≥ 0.7, while the side folds onto the platen (ccx itself: one thread, the same deck).
    # One CI rehearsal (stop 26) met a run 1.04e-3 off at ε ≥ 0.6 (10 of 45 points); 4 fresh runs the same day
    # gave the table's numbers exactly. Its tolerance is that scatter, 2e-3; the other two points hold to 1e-6.
    # Once in CI (seventh stop) one of the three fresh runs stopped short, which the fresh runs of the
    # retried point did not (12 of 12 finished): a stop is run once more from an empty cache, and the numbers of a finished run
    # must still match
    for (mu, h0_d0, n, eps0), rtol, atol in (((0.2, 1.0, 0.4, 0.02), 1e-6, 1e-7), ((0.05, 1.6, 0.2, 0.1), 1e-6, 1e-7),
                                             ((0.3, 1.6, 0.4, 0.02), 2e-3, 1e-4)):
        i, j, k, m = (list(z[axis]).index(v) for axis, v in (("mu", mu), ("h0_d0", h0_d0), ("n", n), ("eps0", eps0)))
        for attempt in range(2):
            monkeypatch.setenv("FLOWCURVE_FE_CACHE", str(tmp_path / f"{mu}-{h0_d0}-{n}-{eps0}-{attempt}"))
            run = sample_run((mu, h0_d0, n, eps0))
            if run["completed"]:
                break
        assert not run["cached"] and run["completed"], ((mu, h0_d0, n, eps0), run["reached_strain"], run["settings"], run["message"])
        np.testing.assert_allclose(run["factor_raw"], z["force_factor_raw"][i, j, k, m], rtol=rtol)
        np.testing.assert_allclose(run["bulge"], z["bulge_dR_over_h"][i, j, k, m], rtol=min(10 * rtol, 2e-3), atol=atol)


def test_table_start_points_regenerate_with_ccx(tmp_path, monkeypatch):
    """Two of the table's start runs (short, on ε_p), run again (no cache), give the same numbers."""
    from flowcurve.identification.fe.make_table import sample_start_run
    from flowcurve.identification.fe.model.table import PACKAGE_TABLE

    monkeypatch.setenv("FLOWCURVE_FE_CACHE", str(tmp_path))
    z = np.load(PACKAGE_TABLE)
    for mu, h0_d0, n, eps0 in ((0.2, 1.0, 0.4, 0.02), (0.1, 2.5, 0.05, 0.1)):
        i, j, k, m = (list(z[axis]).index(v) for axis, v in (("mu", mu), ("h0_d0", h0_d0), ("n", n), ("eps0", eps0)))
        run = sample_start_run((mu, h0_d0, n, eps0))
        assert not run["cached"] and run["completed"], ((mu, h0_d0, n, eps0), run["reached_plastic_strain"], run["message"])
        np.testing.assert_allclose(run["factor_raw"], z["start_force_factor_raw"][i, j, k, m], rtol=1e-6)


SEED_LAW_CAUSE = ("measured against the record's own factor (its run over a μ = 0 run of the same model), the table's is within "
                  "0.3 % to ε 0.2, then 1.1 % high at ε 0.41, where the record's own force dips 2 % as its side folds onto the "
                  "platen, and 1.2 % low at 0.5, where the table's runs dip. A finer record mesh (36 or 48 elements) keeps ±1 % "
                  "dips and reads 3.2–3.5 %")
VOCE_CAUSE = ("Voce at μ 0.17, h0/d0 1.8, to ε 0.7: the bulge hardly grows with μ there (0.01 mm of dmax moves μ by 0.1) and the "
              "table's runs at μ ≥ 0.15 on h0/d0 1.6–2.5 stop near ε 0.4–0.7 (also on 80 or 50 increments) and are continued beyond — both flagged. (Its "
              "record used to stop at ε 0.60, where dmax read 0.190; it now runs to 0.7 with 80 increments)")
LIMITS = {3: "μ read 0.211 (the curve within 1.4 %): " + VOCE_CAUSE,
          5: "seed law at μ 0.28, h0/d0 1.2: μ read 0.278, the curve 2.12 % off at ε 0.45 (flagged): " + SEED_LAW_CAUSE}
CASES = [pytest.param(c, marks=pytest.mark.xfail(strict=True, reason=LIMITS[k])) if k in LIMITS else c for k, c in enumerate(VALIDATION_CASES)]


def _read(case, end_face: bool = False):
    ident = identify_compression(upsetting_record(run_case(case), seed=3, toe_mm=0.0, end_face=end_face))
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
    for end_face in (False, True):  # μ from the bulge, and from the original end face
        ident, err = _read(case, end_face=end_face)
        missed = abs(ident.result["friction_mu"] - case["mu"]) > 0.02 or err > 0.02
        flagged = [w for w in ident.result["warnings"] if w.startswith("FE table:")]
        if missed:
            assert flagged, (end_face, ident.result["friction_mu"], err)


@pytest.mark.parametrize("case", VALIDATION_CASES, ids=[c["name"] for c in VALIDATION_CASES])
def test_the_true_mu_is_inside_the_reported_range(case):
    """friction_mu_range (the μ of the bulge ± dmax's 0.01 mm and the FE model form's 5 % of it) holds
    the true μ on every record, also where the point value misses ±0.02 because the barrel hardly
    grows with μ (near sticking): Voce at μ 0.17 reads 0.220 in 0.175–0.35. Counting dmax's
    resolution alone, that range began at 0.184 and missed."""
    ident, _ = _read(case)
    lo, hi = ident.result["friction_mu_range"]
    assert lo - 0.005 <= case["mu"] <= hi + 0.005, (lo, hi)


FACE_LIMITS = {5: "seed law at μ 0.28, h0/d0 1.2: the end face gives μ 0.286, the curve 2.06 % off at ε 0.46: " + SEED_LAW_CAUSE}


@pytest.mark.parametrize("case", [pytest.param(c, marks=pytest.mark.xfail(strict=True, reason=FACE_LIMITS[k])) if k in FACE_LIMITS else c
                                  for k, c in enumerate(VALIDATION_CASES)], ids=[c["name"] for c in VALIDATION_CASES])
def test_with_the_end_face_the_default_reads_fe_records(case):
    """With the original end face measured (post.dface_mm; the record's rim node, another mesh
    than the table's), the default reads μ from it: steel 45, whose barrel hardly tells μ near
    sticking (dmax ± 0.01 mm spans μ 0.22–0.28), reads 0.250 and its curve 1.5 % off."""
    ident, err = _read(case, end_face=True)
    assert ident.result["friction_details"]["fe_table"]["mu_basis"] == "original end face (dface)"
    assert ident.result["friction_mu"] == pytest.approx(case["mu"], abs=0.02)
    assert err < 0.02


def test_the_end_face_tells_mu_on_every_record():
    """μ from the end face within 0.015 of the truth on all six records (measured: at most
    0.0079, Voce at μ 0.17; from the bulge up to 0.050), its range (dface ± 0.01 mm and the FE
    model form's ± 0.02 of d/d_n, §4a.7) holding the truth (with the mesh's ± 0.005 alone it was
    0.006–0.017 wide)."""
    for case in VALIDATION_CASES:
        ident, _ = _read(case, end_face=True)
        lo, hi = ident.result["friction_mu_range"]
        assert ident.result["friction_mu"] == pytest.approx(case["mu"], abs=0.015), case["name"]
        assert lo <= ident.result["friction_mu"] <= hi and lo <= case["mu"] <= hi, (case["name"], lo, hi)


def test_the_force_factor_follows_the_hardening_near_the_strain():
    """The Voce record's own force factor (its run over a μ = 0 run of the same model, both
    CalculiX) against the table's at the true μ: read at the law's local Swift exponent it is
    within 0.8 % over ε 0.05–0.6 (measured 0.51 %); read at the whole curve's Swift fit it is
    1.9 % too high at ε 0.6, where the saturating law hardly hardens any more."""
    import math
    from dataclasses import replace

    from flowcurve.identification.fe.make_table import plastic_strain_at
    from flowcurve.identification.fe.synthetic import case_model
    from flowcurve.identification.fe.model.table import UpsettingTable, local_swift_exponent, swift_hardening
    from flowcurve.identification.fe.model.upsetting import simulate_upsetting

    case = VALIDATION_CASES[3]
    flow, model = case_flow(case), case_model(case)

    def ratio(run):  # F/(σ_f(ε_p)·A)
        eps_p = plastic_strain_at(run.strain, flow, E=model.E_MPa)
        return run.force_N / (flow(eps_p) * math.pi * model.d0_mm**2 * model.h0_mm / (4.0 * run.height_mm))

    run = run_case(case)
    still = simulate_upsetting(replace(run.model, mu=0.0), require_complete=False)  # the same increments as the record
    sel = (run.strain >= 0.05) & (run.strain <= 0.6)
    eps = run.strain[sel]
    own = ratio(run)[sel] / np.interp(eps, still.strain, ratio(still))
    grid = np.linspace(0.0, 0.75, 600)
    n_all, eps0 = swift_hardening(grid, flow(grid))
    table = UpsettingTable.load()
    h0_d0 = model.h0_mm / model.d0_mm
    local = table.force_factor_at(case["mu"], h0_d0, local_swift_exponent(grid, flow(grid), eps0, eps), eps, eps0=eps0)
    whole = table.force_factor_at(case["mu"], h0_d0, n_all, eps, eps0=eps0)
    assert np.max(np.abs(own / local - 1.0)) < 0.008
    assert whole[-1] / own[-1] - 1.0 > 0.01
