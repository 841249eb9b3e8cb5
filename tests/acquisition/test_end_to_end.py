"""End to end: virtual tension and compression tests recorded through the real drivers (the
virtual devices opened in-process, on model time; on ptys in real time with ``-m pty``),
identified, and compared with the virtual material the rig was built from."""

import numpy as np
import pytest

from flowcurve.demo import (demo_specs, demo_time_scale, friction_comparison, friction_comparison_lines, identify_and_write, neck_comparison,
                            neck_comparison_lines, summary_lines)
from flowcurve.record.format import read_record
from flowcurve.acquisition.session import run_virtual_test
from flowcurve.identification.identify import identify

MATERIAL = "steel45"
TIME_SCALE = 15.0


def max_dev_pct(fit, run, lo, hi):
    """Max |A + B εp^n over the JC truth − 1| on [lo, hi], computed here from the fit dict."""
    eps = np.linspace(lo, hi, 300)
    fitted = fit["A_MPa"] + fit["B_MPa"] * eps ** fit["n"]
    truth = run.material.flow_stress(eps, run.strain_rate_per_s, run.temperature_C)
    return 100 * np.max(np.abs(fitted / truth - 1))


def test_virtual_tension_identified_within_3_percent_up_to_the_neck(tmp_path, device_link):
    # the default rig: its neck from CalculiX runs, not from the neck corrections' own formulas
    spec = demo_specs(MATERIAL)[0]
    run = run_virtual_test(spec, tmp_path / "t.csv", material=MATERIAL, time_scale=demo_time_scale(spec, TIME_SCALE), **device_link)
    assert run.outcome.status == "complete" and "fracture" in run.outcome.reason
    rec = read_record(run.outcome.path)
    assert rec.test == "tension" and not rec.truncated
    assert rec.meta["virtual.tension_response"] == "fe" and "tension response fe" in rec.meta["rig.virtual"]
    assert float(rec.meta["post.lu_mm"]) > 30.0
    ident, folder = identify_and_write(run.outcome.path, tmp_path / "results")
    res = ident.result
    assert (folder / "result.json").exists() and (folder / "true_curve.csv").exists()
    assert any(folder.glob("*.png"))
    assert "fracture true strain" in "\n".join(summary_lines(run, ident, folder))  # the demo's report
    hard = res["hardening"]
    # the strain range the test reached: up to the fracture point (uniform part + neck)
    hi = min(hard["strain_range"][1], res["fracture_true_strain"])
    assert hi > 0.3
    assert max_dev_pct(hard, run, 0.002, res["uniform_true_plastic_strain"]) < 3.0
    # past necking, the neck corrections' real error on the FE neck: Davidenkov with the FE
    # profile radius reads the fracture stress 3.3 % high (flowcurve demo, docs/methods.md §3.6)
    assert max_dev_pct(hard, run, 0.002, hi) < 5.0
    table = neck_comparison(rec, ident, run)
    truth = run.material.flow_stress(res["fracture_true_strain"], run.strain_rate_per_s, run.temperature_C)
    davidenkov = res["neck_corrections"]["davidenkov"]["stress_MPa"]
    assert table["rows"][0]["error_pct"]["davidenkov"] == pytest.approx(100 * (davidenkov / truth - 1), abs=1e-9)
    assert 0.0 < table["rows"][0]["error_pct"]["davidenkov"] < 5.0  # blunter than Le Roy's neck: under-corrected
    assert [r["source"] for r in table["rows"]] == ["measured neck radius", "Le Roy et al. (1981)"]
    assert "davidenkov" in "\n".join(neck_comparison_lines(table, run))
    # Rm against Considere's closed form on the true law: max over eps of sigma(eps)·exp(-eps)
    eps = np.linspace(1e-4, 1.0, 20001)
    rm_true = np.max(run.material.flow_stress(eps, run.strain_rate_per_s, run.temperature_C) * np.exp(-eps))
    assert res["Rm_MPa"] == pytest.approx(rm_true, rel=0.01)


def test_virtual_tension_on_the_bridgman_mirror_is_read_exactly_by_bridgman(tmp_path, device_link):
    # the analytic rig (Bridgman's factor with Le Roy's a/R, the neck radius from the same law):
    # Bridgman with the measured radius inverts exactly what made the record
    spec = demo_specs(MATERIAL)[0]
    run = run_virtual_test(spec, tmp_path / "t.csv", material=MATERIAL, time_scale=demo_time_scale(spec, TIME_SCALE), tension_response="bridgman",
                           **device_link)
    assert run.outcome.status == "complete" and run.tension_response == "bridgman"
    rec = read_record(run.outcome.path)
    assert rec.meta["virtual.tension_response"] == "bridgman"
    res = identify(rec).result
    truth = run.material.flow_stress(res["fracture_true_strain"], run.strain_rate_per_s, run.temperature_C)
    assert res["neck_corrections"]["bridgman"]["stress_MPa"] == pytest.approx(truth, rel=5e-3)
    assert max_dev_pct(res["hardening"], run, 0.002, res["fracture_true_strain"]) < 3.0


def seed_mu_of_the_fe_barrel(run, h0_d0, eps):
    """The μ the seed's (3.19) reads from the barrel the FE runs give at the rig's inputs: the
    npz's ΔR/h at the true μ (a grid value), linear in ln(h0/d0), n and ε, n the material's
    log-log slope over εp 0.05–0.9, then (3.19) inverted by hand."""
    from flowcurve.rig.virtual.fe_response import DATA

    e = np.linspace(0.05, 0.9, 60)
    n = np.polyfit(np.log(e), np.log(run.material.flow_stress(e)), 1)[0]
    with np.load(DATA) as z:
        i = int(np.flatnonzero(np.isclose(z["mu"], run.friction_mu))[0])
        lh, ns, b = np.log(z["h0_d0"]), z["n"], z["bulge_dR_over_h"][i]
        j = np.searchsorted(lh, np.log(h0_d0)) - 1
        k = np.searchsorted(ns, n) - 1
        wj, wk = (np.log(h0_d0) - lh[j]) / (lh[j + 1] - lh[j]), (n - ns[k]) / (ns[k + 1] - ns[k])
        col = (1 - wj) * (1 - wk) * b[j, k] + wj * (1 - wk) * b[j + 1, k] + (1 - wj) * wk * b[j, k + 1] + wj * wk * b[j + 1, k + 1]
        dR_h = np.interp(eps, z["strain"], col)
    return (np.log(1 - dR_h * eps**-0.83 / 0.0683) / -26.7) ** (1 / 1.53)  # (3.19)


def test_virtual_compression_identified_and_friction_recovered(tmp_path, device_link):
    spec = demo_specs(MATERIAL)[1]
    # slower than the tension test: the stiff short specimen leaves few samples on the elastic line
    run = run_virtual_test(spec, tmp_path / "c.csv", material=MATERIAL, time_scale=10.0, friction_mu=0.1,
                           **device_link)
    assert run.outcome.status == "complete" and run.compression_response == "fe"
    rec = read_record(run.outcome.path)
    h0, hk, d0 = float(rec.meta["specimen.h0_mm"]), float(rec.meta["post.hk_mm"]), float(rec.meta["specimen.d0_mm"])
    reached = np.log(h0 / hk)  # true strain the test reached
    # the virtual rig's force and barrel come from CalculiX runs; the default identification
    # (fe_table) reads a table of the same runs, interpolated its own way (PCHIP along μ) and
    # with the hardening exponent of the measured curve: μ within 0.01, the curve within 3 %
    ident = identify(rec)
    res = ident.result
    assert res["friction_method"] == "fe_table" and res["friction_correction"] == "fe_table"
    assert "friction μ" in "\n".join(summary_lines(run, ident, tmp_path))  # the demo's report
    assert res["friction_mu"] == pytest.approx(run.friction_mu, abs=0.01)
    assert res["E_source"] == "record (material.E_MPa)"  # the handbook E the virtual operator entered
    dev = max_dev_pct(res["hardening"], run, 0.002, reached)
    assert dev < 3.0, f"compression hardening {dev:.1f} % off (E {res.get('E_MPa')} MPa, warnings {res.get('warnings')})"
    # the seed's regression (3.18)/(3.19) was fitted to other FE runs: it reads the FE barrel
    # with its real error, the one (3.19) of the FE ΔR/h at the rig's true inputs has
    seed_expected = seed_mu_of_the_fe_barrel(run, h0 / d0, reached)
    assert res["friction"]["bulge_regression"] == pytest.approx(seed_expected, abs=0.003)
    assert abs(seed_expected - run.friction_mu) > 0.01  # not a mirror any more: the seed errs here
    # the demo's table: every friction method, μ and the corrected curves' errors
    table = friction_comparison(rec, run, default=ident)
    rows = {r["method"]: r for r in table["rows"]}
    assert rows["fe_table"]["mu"] == res["friction_mu"] and rows["bulge_regression"]["mu"] == pytest.approx(seed_expected, abs=0.003)
    assert rows["fe_table"]["error_pct"]["fe_table"] < 3.0
    text = "\n".join(friction_comparison_lines(table, run))
    assert all(m in text for m in rows) and all(c in text for c in table["corrections"])


def test_virtual_compression_on_the_slab_mirror_is_read_exactly_by_the_seed(tmp_path, device_link):
    # the analytic rig (slab force, (3.18) barrel): the seed's (3.19) with the slab correction
    # inverts exactly what made the record
    spec = demo_specs(MATERIAL)[1]
    run = run_virtual_test(spec, tmp_path / "c.csv", material=MATERIAL, time_scale=10.0, friction_mu=0.1,
                           compression_response="slab", **device_link)
    assert run.outcome.status == "complete"
    rec = read_record(run.outcome.path)
    assert "compression response slab" in rec.meta["rig.virtual"]
    reached = np.log(float(rec.meta["specimen.h0_mm"]) / float(rec.meta["post.hk_mm"]))
    res = identify(rec, friction_method="bulge_regression", friction_correction="slab").result
    assert res["friction_mu"] == pytest.approx(run.friction_mu, abs=0.01)
    dev = max_dev_pct(res["hardening"], run, 0.002, reached)
    assert dev < 3.0, f"compression hardening {dev:.1f} % off (E {res.get('E_MPa')} MPa, warnings {res.get('warnings')})"


def test_the_demo_tension_test_conforms_to_iso_6892_1(tmp_path, device_link):
    """The demo's defaults make a conforming test: its record's rates, measured per phase from the
    crosshead, are ISO 6892-1 method A range 2 throughout (0.05 mm/s was 'testing rate not conforming')."""
    spec = demo_specs(MATERIAL)[0]
    run = run_virtual_test(spec, tmp_path / "t.csv", material=MATERIAL, time_scale=demo_time_scale(spec, TIME_SCALE), **device_link)
    assert run.outcome.status == "complete"
    ident, _ = identify_and_write(run.outcome.path, tmp_path / "results")
    conf = ident.result["methods"]["conformity"]
    rate = conf["testing_rate"]
    # a rate and its u are one claim: the elastic line spans ~5 samples, ~1 encoder count. One record's three claims are
    # judged at 3 u (a k = 2 interval misses one claim in twenty by design: three of them would fail one run in seven);
    # the coverage of U at k = 2 over many records is tests/uncertainty/test_conformity_rate_u.py's
    for phase in ("elastic", "yield", "to_Rm"):
        got = rate["phases"][phase]
        assert abs(got["strain_rate_per_s"] - 0.00025) <= max(0.05 * 0.00025, 3.0 * got["strain_rate_u_per_s"]), (phase, got)
    # the demo conforms: its verdict says so, or names the rate as not resolved — never "not conforming"
    assert (rate["conforms"] is True and rate["designation"] == "ISO 6892-1:2019 A222") or (
        rate["conforms"] is None and rate["designation"].endswith("(testing rate not resolved)")), rate["findings"]
    assert conf["temperature"]["conforms"] is True  # the record states 20 °C
