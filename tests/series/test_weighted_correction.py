"""Every fit point carries its stated uncertainty (issue 45, docs/methods.md §5.10), checked against known truth:
the 4340 Johnson–Cook series of conftest.py (A 792, B 510, n 0.26, C 0.014, m 1.03) with a friction correction
that is uncertain and biased on some members, a strain zero stated by a result folder, the fold-over band's
growth, and the rate term through the law's own slope."""

from __future__ import annotations

import json

import numpy as np
import pytest

from flowcurve.identification.fe.model import model_form as mf
from flowcurve.identification.laws.base import get_law
from flowcurve.identification.series.law_fit import stack_points, stack_terms
from flowcurve.identification.series.point_uncertainty import effective_u, fold_over_u, law_slopes
from flowcurve.identification.series.series import SeriesMember, fit_series, member_from_result

SIEBEL_SHARE = 0.3  # ∂σ/∂μ = −0.3·σ: Siebel's d/3h of a d0 = h0 cylinder (quality.uncertainty.flow_stress_budget)
MU_BIAS, MU_U = 0.1, 0.1  # the biased members' μ is off by 0.1 and say so: u(μ) 0.1


def biased_series(syn, *, stated: bool) -> list[SeriesMember]:
    """The synthetic series; its two 600 °C members corrected with a μ 0.1 too high (σ low by 3 %), stating
    u(μ) and ∂σ/∂μ when ``stated``."""
    members = syn.members(seed=11)
    for m in members:
        if m.temperature_C == 600.0:
            sensitivity = -SIEBEL_SHARE * m.stress_MPa
            m.stress_MPa = m.stress_MPa + MU_BIAS * sensitivity  # σ(μ + δμ) = σ + δμ·∂σ/∂μ
            if stated:
                m.friction_mu_u, m.dsigma_dmu_MPa = MU_U, sensitivity
    return members


def test_weighted_fit_recovers_the_true_constants_despite_a_biased_friction_correction(syn):
    """Unweighted the biased members pull m (and the law at 600 °C); weighted by u(μ)·|∂σ/∂μ| they weigh
    ~1/60 of the others, and every constant lands within two of its stated total uncertainties."""
    ref = syn.REF
    plain = fit_series(biased_series(syn, stated=False), **ref)
    weighted = fit_series(biased_series(syn, stated=True), **ref)
    true = syn.TRUE
    err = {name: {p: abs(sf.fit.params[p] / true[p] - 1.0) for p in true} for name, sf in (("plain", plain), ("weighted", weighted))}
    assert err["weighted"]["m"] < 0.5 * err["plain"]["m"], err
    assert max(err["weighted"].values()) < max(err["plain"].values()), err
    total = weighted.as_dict()["total_uncertainty"]
    keys = {p.name: p.key for p in weighted.fit.law.parameters}
    for p, value in true.items():
        assert abs(weighted.fit.params[p] - value) <= 2.0 * total[keys[p]], (p, weighted.fit.params[p], total[keys[p]])
    # the law at 600 °C: the biased members' conditions, read from the others
    eps = np.linspace(0.01, 0.3, 30)
    dev = {name: np.max(np.abs(sf.fit(eps, 1.0, 600.0) / syn.true_stress(eps, 1.0, 600.0) - 1.0))
           for name, sf in (("plain", plain), ("weighted", weighted))}
    assert dev["weighted"] < 0.01 and dev["weighted"] < 0.5 * dev["plain"], dev
    law = weighted.as_dict()["law"]
    assert law["point_u_terms"] == ["floor", "friction"], law["point_u_terms"]
    assert plain.as_dict()["law"]["point_u_terms"] == ["floor"]


def test_friction_term_is_u_mu_times_the_sensitivity(syn):
    members = biased_series(syn, stated=True)
    eps, sig, _, _, u, idx = stack_points(members, 60)
    floor = u[idx == 0][0]
    for i, m in enumerate(members):
        expected = np.hypot(floor, MU_U * SIEBEL_SHARE * np.interp(eps[idx == i], m.plastic_strain, m.stress_MPa / (1 - MU_BIAS * SIEBEL_SHARE))) \
            if m.temperature_C == 600.0 else np.full((idx == i).sum(), floor)
        assert u[idx == i] == pytest.approx(expected, rel=1e-9), m.name


def test_a_member_whose_result_states_its_strain_zero_weighs_less_at_small_strain(syn, tmp_path):
    """result.json's hardening.start_uncertainty.delta_eps0 reaches the member; its first points carry the
    stress the true curve moves over ±δε0 (the closed form's), its late ones the floor; the friction
    result's μ range and true_curve.csv's dsigma_dmu_MPa reach it as u(μ) and ∂σ/∂μ."""
    m = syn.members(noise_MPa=0.0, points=300)[0]
    plain = syn.write_result_folder(tmp_path / "plain", m, test="compression")
    stated = syn.write_result_folder(tmp_path / "stated", m, test="compression")
    result = json.loads((stated / "result.json").read_text())
    result.update(hardening={"start_uncertainty": {"delta_eps0": 0.004}}, friction_mu_range=[0.08, 0.12])
    (stated / "result.json").write_text(json.dumps(result))
    curve = (stated / "true_curve.csv").read_text().splitlines()
    curve = [curve[0] + ",dsigma_dmu_MPa"] + [f"{line},{-0.3 * float(line.split(',')[1]):.8g}" for line in curve[1:]]
    (stated / "true_curve.csv").write_text("\n".join(curve) + "\n")
    a, b = member_from_result(plain), member_from_result(stated)
    assert a.delta_eps0 is None and b.delta_eps0 == 0.004
    assert b.friction_mu_u == pytest.approx(0.02) and b.dsigma_dmu_MPa == pytest.approx(-0.3 * b.stress_MPa, rel=1e-6)
    b.friction_mu_u = None  # the start alone
    _, _, _, _, u_a, _ = stack_points([a], 60)
    eps, sig, rate, temp, u_b, _ = stack_points([b], 60)
    floor = 0.004 * np.sqrt(np.mean(sig**2))
    shift = np.abs(syn.true_stress(eps + 0.004, rate, temp) - syn.true_stress(np.maximum(eps - 0.004, eps[0]), rate, temp)) / 2
    assert u_b[0] == pytest.approx(np.hypot(floor, shift[0]), rel=0.02)
    assert u_a[0] == pytest.approx(floor, rel=0.2)  # one sample's 0.001/√12: the floor dominates
    assert u_b[0] > 3 * u_a[0]
    assert u_b[-1] == pytest.approx(floor, rel=0.05)


def test_fold_over_term_grows_over_the_band_only():
    """The correction's stated uncertainty (fe.model.model_form: 1.2 % at μ 0.1, grown to 3 % over the 0.1
    band before a fold-over at ε 0.5): the fold-over term is 0 before the band, σ·(u − 1.2 %) in it."""
    eps = np.linspace(0.002, 0.6, 200)
    sig = 300.0 * (0.01 + eps) ** 0.2
    u_pct = mf.corrected_stress_uncertainty_pct(eps, 0.1, 0.5)
    m = SeriesMember("fold", eps, sig, 0.01, 20.0, correction_u_pct=u_pct)
    got = fold_over_u(m, eps, sig)
    base = 100.0 * mf.force_model_form(0.1)
    assert got[eps < 0.4] == pytest.approx(0.0, abs=1e-12)
    assert got[eps >= 0.5] == pytest.approx(sig[eps >= 0.5] * (mf.FOLD_OVER_SIGMA_FACTOR * mf.FORCE_SIGMA_PCT - base) / 100.0)
    _, _, _, _, _, terms = stack_terms([m], 60)
    assert terms.terms() == ["floor", "correction_form", "fold_over"]


def test_rate_term_weighs_only_where_the_law_is_rate_sensitive(syn):
    """Johnson–Cook is flat below its reference rate (ln ε̇* clamped at 0): a stated u(ln ε̇) 0.5 leaves the
    0.1 1/s members' weights alone and adds ∂σ/∂ln ε̇·u = (A + B·εp^n)·C·(1 − T*^m)·0.5 at 100 1/s; the
    second pass still reads the true constants."""
    members = syn.members(rates=(0.1, 1.0, 100.0))
    for m in members:
        m.strain_rate_u_ln = 0.5
    eps, sig, rate, temp, idx, terms = stack_terms(members, 60)
    law = get_law("johnson_cook")
    slopes = law_slopes(law, {**syn.TRUE, **syn.REF}, eps, rate, temp)
    u_eff = effective_u(terms, slopes)
    slow, fast = rate < 1.0, rate > 10.0
    assert u_eff[slow] == pytest.approx(terms.u[slow], rel=1e-12)
    t_star = (temp - syn.REF["ref_temperature_C"]) / (syn.REF["melt_temperature_C"] - syn.REF["ref_temperature_C"])
    closed = (syn.TRUE["A"] + syn.TRUE["B"] * eps**syn.TRUE["n"]) * syn.TRUE["C"] * (1 - t_star ** syn.TRUE["m"]) * 0.5
    assert u_eff[fast] == pytest.approx(np.hypot(terms.u[fast], closed[fast]), rel=1e-3)
    sf = fit_series(members, **syn.REF)
    assert "rate" in sf.fit.point_u_terms
    for p in ("A", "B", "n", "m"):
        assert sf.fit.params[p] == pytest.approx(syn.TRUE[p], rel=0.02), (p, sf.fit.params)
    assert sf.fit.params["C"] == pytest.approx(syn.TRUE["C"], rel=0.1)


def test_a_compression_record_hands_its_stated_uncertainties_to_its_member(tmp_path):
    """identify's δε0, u(μ) (half friction_mu_range) and the applied correction's ∂σ/∂μ reach the member, from
    the record and from the result folder it writes (true_curve.csv's dsigma_dmu_MPa column)."""
    from flowcurve.identification.identify import identify
    from flowcurve.identification.series.series import member_from_record

    from .compression_series import E_MPa, compression_record

    rec, _ = compression_record(20.0, 0.005, mu=0.1, response="fe")
    ident = identify(rec, E_MPa=E_MPa)
    result = ident.result
    folder = ident.write(tmp_path / "C1")
    for m in (member_from_record(rec, E_MPa=E_MPa), member_from_result(folder)):
        assert m.delta_eps0 == pytest.approx(result["hardening"]["start_uncertainty"]["delta_eps0"], rel=1e-5)
        lo, hi = result["friction_mu_range"]
        assert m.friction_mu_u == pytest.approx((hi - lo) / 2.0, rel=1e-5)
        applied = ident.curves["true_fe_table"]
        expected = np.interp(m.plastic_strain, applied["true_plastic_strain"], applied["dsigma_dmu_MPa"])
        assert m.dsigma_dmu_MPa == pytest.approx(expected, rel=1e-3, abs=1e-3)
        assert np.all(m.dsigma_dmu_MPa < 0)  # more friction, a lower flow stress from the same pressure
