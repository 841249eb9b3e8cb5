"""identify_tension on synthetic records made from a known law, frame and toe."""

import math

import numpy as np
import pytest
from scipy.optimize import brentq, minimize_scalar

from flowcurve.errors import FlowcurveError, IdentificationError, RecordError
from flowcurve.identification.indicator import frame_stiffness_from_known_modulus
from flowcurve.identification.tension.identify import identify_tension
from flowcurve.identification.tension.values import bulk_modulus, true_plastic_strain, true_stress_constant_volume, true_stress_gost

from flowcurve.identification.laws.hardening import johnson_cook_static

T = dict(E_MPa=200_000.0, A=400.0, B=600.0, n=0.3)


def law(eps_p):
    return johnson_cook_static(eps_p, T["A"], T["B"], T["n"])


def rp02_closed_form():
    """Rp0.2 of the generator's material by root-finding in its own parametrisation."""
    def g(sig_t):
        eps = ((sig_t - T["A"]) / T["B"]) ** (1 / T["n"]) + sig_t / T["E_MPa"]
        e = math.expm1(eps)
        return e - sig_t / (1 + e) / T["E_MPa"] - 0.002
    sig_t = brentq(g, T["A"] + 1e-9, T["A"] + T["B"])
    eps = ((sig_t - T["A"]) / T["B"]) ** (1 / T["n"]) + sig_t / T["E_MPa"]
    return sig_t / (1 + math.expm1(eps))


def rm_considere():
    """Rm as the maximum of σ_t·exp(−ε) over the continuous law (Considère)."""
    res = minimize_scalar(lambda ep: -law(ep) * math.exp(-(ep + law(ep) / T["E_MPa"])), bounds=(1e-4, 0.6), method="bounded",
                          options={"xatol": 1e-10})
    return -res.fun, res.x


# -- formulas ---------------------------------------------------------------------------------

def test_gost_true_stress_limits_and_defining_relation():
    s_e = np.array([100.0, 500.0, 900.0])
    eps = np.array([0.001, 0.05, 0.2])
    # K → ∞: σ_e/(1 − ε)
    assert np.allclose(true_stress_gost(s_e, eps, 1e15), s_e / (1 - eps), rtol=1e-9)
    # small strain: ≈ σ_e(1 + e) to second order
    small = np.array([1e-4, 1e-3])
    assert np.allclose(true_stress_gost(300.0, np.log1p(small), 1e15), true_stress_constant_volume(300.0, small), rtol=2e-6)
    # the defining relation F = F0(1 − ε + σ_t/(3K)): σ_t(1 − ε + σ_t/(3K)) = σ_e
    K = bulk_modulus(200_000.0, 0.3)
    assert K == pytest.approx(200_000.0 / 1.2)
    st = true_stress_gost(s_e, eps, K)
    assert np.allclose(st * (1 - eps + st / (3 * K)), s_e, rtol=1e-12)
    assert true_plastic_strain(0.1, 600.0, 200_000.0) == pytest.approx(0.1 - 0.003)


def test_bulk_modulus_rejects_impossible_poisson():
    with pytest.raises(IdentificationError, match="Poisson"):
        bulk_modulus(200_000.0, 0.5)


# -- extensometer path ---------------------------------------------------------------------------

def test_extensometer_path_recovers_iso_results_and_law(synthetic):
    rec, info = synthetic()
    res = identify_tension(rec, true_stress="constant_volume")
    r = res.result
    assert r["methods"]["strain_source"] == "extensometer"
    # the engineering σ_e–e slope of a material Hookean in true measures is E·(1 − ~1.5e):
    # over the window (e ≲ 0.0016) it is a few tenths of a percent below E
    assert r["E_MPa"] == pytest.approx(T["E_MPa"], rel=5e-3)
    assert r["Rp02_MPa"] == pytest.approx(rp02_closed_form(), rel=2e-4)
    rm, ep_m = rm_considere()
    assert r["Rm_MPa"] == pytest.approx(rm, rel=1e-5)
    assert r["uniform_true_plastic_strain"] == pytest.approx(ep_m, abs=2e-3)
    assert r["Ag_pct"] == pytest.approx(100 * (math.expm1(ep_m + law(ep_m) / T["E_MPa"]) - rm / T["E_MPa"]), abs=0.05)
    assert r["Z_pct"] == pytest.approx(100 * (1 - math.exp(-0.8)), rel=1e-9)
    assert r["fracture_true_strain"] == pytest.approx(0.8, rel=1e-9)
    assert r["fracture_true_stress_MPa"] == pytest.approx(law(0.8), rel=1e-5)
    h = r["hardening"]
    assert (h["A_MPa"], h["B_MPa"], h["n"]) == pytest.approx((T["A"], T["B"], T["n"]), rel=2e-3)
    # the three-point JC solution goes through the same exact points
    tp = r["hardening_alternatives"]["three_point_johnson_cook"]
    assert (tp["A_MPa"], tp["B_MPa"], tp["n"]) == pytest.approx((T["A"], T["B"], T["n"]), rel=5e-3)
    # the true curve is the law
    tc = res.true_curve
    sel = tc["true_plastic_strain"] > 0.002
    assert np.allclose(tc["true_stress_MPa"][sel], law(tc["true_plastic_strain"][sel]), rtol=2e-4)
    assert set(res.curves) >= {"raw_diagram", "corrected_diagram", "engineering", "true", "fit"}
    assert r["neck_corrections"]["davidenkov"]["stress_MPa"] == pytest.approx(law(0.8))
    assert set(r["neck_corrections"]) >= {"davidenkov", "bridgman", "mirone", "a_over_R"}


def test_default_true_stress_is_the_law_and_the_seeds_form_reads_high_as_its_area_says(synthetic):
    """The default (constant volume) gives the law over the uniform range to 0.05 % (it was the seed's (3.6),
    accepted to 6 %); the seed's form, kept for comparison, reads high by e^(−ε)/(1 − ε + σ/(3K)), the ratio of
    the areas the two forms assume — +0.9 % at the end of this record's uniform range (ε ≈ 0.14; CalculiX
    records to e = 0.4: bench/tension_true_stress_forms.py, docs/methods.md §3.2)."""
    rec, _ = synthetic()
    default = identify_tension(rec)
    assert default.result["methods"]["true_stress"] == "σ_e(1 + e), constant volume"
    tc = default.true_curve
    sel = tc["true_plastic_strain"] > 0.002
    assert np.max(np.abs(tc["true_stress_MPa"][sel] / law(tc["true_plastic_strain"][sel]) - 1)) < 5e-4
    assert default.result["E_MPa"] == pytest.approx(T["E_MPa"], rel=5e-3)
    seed = identify_tension(rec, true_stress="gost_3_6").curves["true"]
    eps, sig = seed["true_strain"].to_numpy(), seed["true_stress_MPa"].to_numpy()
    plastic = seed["true_plastic_strain"].to_numpy() > 0.002
    K = bulk_modulus(default.result["E_MPa"], 0.3)
    area_ratio = np.exp(-eps) / (1 - eps + sig / (3 * K))  # A_constant_volume / A_(3.4)
    ratio = sig / law(seed["true_plastic_strain"].to_numpy())
    np.testing.assert_allclose(ratio[plastic], area_ratio[plastic], rtol=5e-4)
    assert ratio[plastic].max() > 1.008


# -- crosshead path: frame compliance and toe ----------------------------------------------------

def test_crosshead_path_recovers_frame_stiffness_and_law(synthetic):
    rec, info = synthetic(extensometer=False)
    window_N = (0.2 * T["A"] * info["s0_mm2"], 0.8 * T["A"] * info["s0_mm2"])
    C = frame_stiffness_from_known_modulus(rec.column("crosshead_mm"), rec.column("force_N"), E_MPa=T["E_MPa"],
                                           area_mm2=info["s0_mm2"], length_mm=30.0, window_N=window_N)
    # within the few 0.1 % by which the engineering elastic line departs from E (see above)
    assert C == pytest.approx(136.0, rel=5e-3)
    r = identify_tension(rec, frame_stiffness_N_per_um=C, crosshead_length_mm=30.0, true_stress="constant_volume").result
    assert r["methods"]["strain_source"] == "crosshead"
    assert r["methods"]["toe_compensation_mm"] == pytest.approx(0.08, abs=1e-3)  # 1 µm
    assert r["E_MPa"] == pytest.approx(T["E_MPa"], rel=5e-3)
    assert r["Rp02_MPa"] == pytest.approx(rp02_closed_form(), rel=2e-4)
    h = r["hardening"]
    assert (h["A_MPa"], h["B_MPa"], h["n"]) == pytest.approx((T["A"], T["B"], T["n"]), rel=3e-3)


def test_crosshead_without_stiffness_warns_and_underestimates_E(synthetic):
    rec, _ = synthetic(extensometer=False)
    r = identify_tension(rec).result
    assert any("frame stiffness" in w for w in r["warnings"])
    # apparent modulus of specimen + frame in series: 1/E_app = 1/E + S0/(L0·C)
    s0 = math.pi * 9
    expected = 1 / (1 / T["E_MPa"] + s0 / (30.0 * 136_000.0))
    assert r["E_MPa"] == pytest.approx(expected, rel=5e-3)
    assert r["E_MPa"] < 0.5 * T["E_MPa"]


def test_scaling_to_measured_lu(synthetic):
    rec, info = synthetic(extensometer=False)
    rec.meta["post.lu_mm"] = "36.0"
    rec.meta["rig.frame_stiffness_N_per_um"] = "136"
    r = identify_tension(rec).result
    assert r["A_pct"] == pytest.approx(20.0)
    assert r["A_method"].startswith("measured")
    # (3.1) like with like: the scaled elongation at the last sample before the break, less the elastic
    # extension the pieces give back there (scaled with it), is Lu − L0 — not the largest elongation
    ident = identify_tension(rec)
    terms, K = ident.result["methods"]["scale_Kl"], ident.result["methods"]["scale_factor_Kl"]
    elong = ident.curves["corrected_diagram"]["elongation_mm"].to_numpy()
    recovery = terms["specimen_recovery_mm"] + terms["frame_recovery_mm"]
    assert elong[terms["fracture_index"]] - K * recovery == pytest.approx(6.0, rel=1e-9)
    assert recovery > 0.0 and terms["frame_recovery_mm"] == 0.0  # the frame's compliance is removed (136 N/µm given)


def test_noisy_record_still_gives_the_law(synthetic):
    rec, _ = synthetic(noise_N=5.0, seed=11)
    r = identify_tension(rec, true_stress="constant_volume").result
    assert r["E_MPa"] == pytest.approx(T["E_MPa"], rel=0.02)
    h = r["hardening"]
    assert h["A_MPa"] == pytest.approx(T["A"], rel=0.03)
    assert h["n"] == pytest.approx(T["n"], rel=0.05)
    assert h["A_MPa_stderr"] is not None


# -- bad input ---------------------------------------------------------------------------------

def test_missing_geometry_names_the_key(synthetic):
    rec, _ = synthetic()
    del rec.meta["specimen.d0_mm"]
    with pytest.raises(RecordError, match="specimen.d0_mm"):
        identify_tension(rec)


def test_force_that_never_rises(synthetic):
    rec, _ = synthetic()
    rec.data["force_N"] = -rec.data["force_N"]
    with pytest.raises(RecordError, match="never rises"):
        identify_tension(rec)


def test_wrong_units_are_suspected(synthetic):
    rec, _ = synthetic()
    rec.data["force_N"] = rec.data["force_N"] * 1000  # kN read as N... the other way round
    with pytest.raises(IdentificationError, match="check units"):
        identify_tension(rec)
    rec, _ = synthetic()
    rec.meta["specimen.extensometer_gauge_mm"] = "0.03"  # metres
    with pytest.raises(IdentificationError, match="check units"):
        identify_tension(rec)


def test_bad_options_are_clear_errors(synthetic):
    rec, _ = synthetic()
    for kw in ({"neck": "bogus"}, {"true_stress": "x"}, {"modulus_window": (0.5, 0.2)}, {"hardening": "magic"}):
        with pytest.raises(FlowcurveError):
            identify_tension(rec, **kw)
    rec2, _ = synthetic(extensometer=False)
    with pytest.raises(RecordError, match="extensometer"):
        identify_tension(rec2, use_extensometer=True)


def test_extensometer_removed_before_fracture_falls_back_to_the_crosshead(synthetic):
    rec, _ = synthetic()
    rec.meta["rig.frame_stiffness_N_per_um"] = "136"
    rec.data.loc[400:, "extensometer_mm"] = np.nan
    r = identify_tension(rec, crosshead_length_mm=30.0, true_stress="constant_volume").result
    assert r["methods"]["strain_source"] == "crosshead"
    assert any("removed before fracture" in w for w in r["warnings"])
    assert r["E_MPa"] == pytest.approx(T["E_MPa"], rel=5e-3)
    with pytest.raises(RecordError, match="no value from sample 401"):
        identify_tension(rec, use_extensometer=True)


def test_result_writes_as_json_with_the_shared_keys(synthetic, tmp_path):
    import json
    rec, _ = synthetic()
    out = identify_tension(rec).write(tmp_path / "r")
    result = json.loads((out / "result.json").read_text())
    for key in ("test", "E_MPa", "Rp02_MPa", "Rm_MPa", "Ag_pct", "A_pct", "Z_pct", "fracture_true_strain",
                "fracture_true_stress_MPa", "hardening", "modulus_window_MPa", "methods", "warnings", "record"):
        assert key in result, key
    assert {"law", "A_MPa", "B_MPa", "n", "fit_error_pct"} <= set(result["hardening"])
    assert (out / "true_curve.csv").read_text().splitlines()[0] == "true_plastic_strain,true_stress_MPa"
