"""A held-out hot upsetting series (hot_series.py: a Hensel–Spittel-like law, 700/800/900 °C × 0.001/0.01/0.1
1/s at constant true strain rate, 50 Hz, the fast records without an elastic window) in ``flowcurve fit``:
every record read, each point's own rate, identify's friction-corrected curve, a record that cannot be
read named (and skipped unless --strict-records), and the adiabatic correction against closed forms.
"""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from flowcurve.cli import main
from flowcurve.identification.series.members import (SeriesMember, adiabatic_temperature_rise_K, member_from_record,
                                                     with_adiabatic_heating)
from flowcurve.record.format import write_record

from .hot_series import DENSITY_KG_PER_M3, E_MPa, HEAT_CAPACITY_J_PER_KG_K, SERIES, flow, hot_record

FIT = ["--E", repr(E_MPa), "--melt-temp", "1450"]
FAST = [(T, r) for T, r in SERIES if r >= 0.01]  # the default selection's series: the 0.001 1/s records are 35 000 samples each


def _write(tmp_path, conditions, **kw):
    return [write_record(tmp_path / f"{rec.source}.csv", rec) for rec in (hot_record(T, r, **kw)[0] for T, r in conditions)]


def test_fast_records_have_no_elastic_window():
    """The premise: at 0.1 1/s one 50 Hz sample is 0.002 strain, more than the whole elastic line."""
    rec, truth = hot_record(800.0, 0.1)
    force = -rec.data["force_N"].to_numpy()
    force = force[: int(np.argmax(force)) + 1]  # the loading
    area = np.pi * 10.0**2 / 4
    yield_force = truth["stress_MPa"][0] * area
    assert np.sum((force > 0.1 * yield_force) & (force < 0.9 * yield_force)) <= 1


def test_hot_series_reads_in_fit(tmp_path, capsys):
    """Every record of the hot series is used by the default (JC) fit; each point carries its own rate,
    which at constant true strain rate is the nominal one."""
    paths = _write(tmp_path, FAST)
    out = tmp_path / "fit"
    assert main(["fit", *map(str, paths), "--out", str(out), *FIT]) == 0, capsys.readouterr().err
    d = json.loads((out / "fit.json").read_text())
    assert {r["name"] for r in d["records"]} == {p.stem for p in paths}
    assert f"over {len(paths)} records" in capsys.readouterr().out
    table = pd.read_csv(out / d["point_rates_file"])
    for name, rows in table.groupby("record"):
        nominal = float(name.split("rate")[1])
        late = rows["true_plastic_strain"] >= 0.02
        assert np.allclose(rows["strain_rate_per_s"][late], nominal, rtol=0.02), name
    assert all(r["temperature_rise_max_K"] is None for r in d["records"])  # no correction asked for


def test_each_curve_follows_the_law_and_its_own_rate():
    for T, r in ((700.0, 0.1), (900.0, 0.01)):
        rec, truth = hot_record(T, r)
        m = member_from_record(rec, E_MPa=E_MPa)
        late = m.plastic_strain >= 0.02
        assert np.max(np.abs(m.stress_MPa[late] / flow(m.plastic_strain[late], r, T) - 1.0)) < 0.02, rec.source
        assert m.point_rates_per_s[late] == pytest.approx(np.interp(m.plastic_strain[late], truth["eps_p"], truth["rate_per_s"]), rel=0.02)


def test_member_takes_identifys_friction_corrected_curve():
    """μ 0.15 on the platens: the member's curve is identify's corrected one (same μ, same points), and
    with the slab correction (the closed form's own friction model) the law within 2 %."""
    from flowcurve.identification.identify import identify
    from flowcurve.identification.outcome import TRUE_CURVE_COLUMNS

    rec, _ = hot_record(800.0, 0.01, mu=0.15)
    options = {"friction_method": "bulge_regression", "friction_correction": "slab"}
    m = member_from_record(rec, E_MPa=E_MPa, **options)
    ident = identify(rec, E_MPa=E_MPa, **options)
    assert m.friction_mu == pytest.approx(ident.result["friction_mu"]) and m.friction_mu > 0.1
    eps, sig = (ident.true_curve[c].to_numpy() for c in TRUE_CURVE_COLUMNS)
    keep = eps >= 0.002
    order = np.argsort(eps[keep], kind="stable")
    assert np.array_equal(eps[keep][order], m.plastic_strain) and np.array_equal(sig[keep][order], m.stress_MPa)
    late = m.plastic_strain >= 0.02
    assert np.max(np.abs(m.stress_MPa[late] / flow(m.plastic_strain[late], 0.01, 800.0) - 1.0)) < 0.02


def test_a_record_that_cannot_be_read_is_named_and_skipped(tmp_path, capsys):
    """A mistyped dmax (below the volume-constant diameter): identification refuses it with a message
    that did not name the file; fit names it, fits the rest and says so — or refuses the series
    with --strict-records, naming it."""
    paths = _write(tmp_path, [(T, 0.1) for T in (700.0, 800.0, 900.0)] + [(T, 0.01) for T in (700.0, 900.0)])
    bad, _ = hot_record(800.0, 0.01, source="typo_dmax")
    bad.meta["post.dmax_mm"] = "5"
    paths.append(write_record(tmp_path / "typo_dmax.csv", bad))
    out = tmp_path / "fit"
    assert main(["fit", *map(str, paths), "--out", str(out), *FIT]) == 0
    captured = capsys.readouterr()
    assert "typo_dmax.csv" in captured.err and "skipped" in captured.err
    d = json.loads((out / "fit.json").read_text())
    assert len(d["records"]) == 5 and "typo_dmax" not in {r["name"] for r in d["records"]}
    assert any("typo_dmax.csv" in w for w in d["warnings"]) and any("fitted on 5 of 6 inputs" in w for w in d["warnings"])
    assert main(["fit", *map(str, paths), "--out", str(tmp_path / "strict"), "--strict-records", *FIT]) == 2
    err = capsys.readouterr().err
    line = next(line for line in err.splitlines() if line.startswith("flowcurve: error: "))
    assert "typo_dmax.csv" in line and "negative bulge" in line


def test_adiabatic_rise_of_a_constant_stress_material():
    """Closed form: σ constant → ΔT = β·σ·εp/(ρ·c_p)."""
    eps = np.linspace(0.002, 0.8, 50)
    sigma = 120.0
    rise = adiabatic_temperature_rise_K(eps, np.full(eps.size, sigma), density_kg_per_m3=7850.0, heat_capacity_J_per_kg_K=650.0)
    assert rise == pytest.approx(0.9 * sigma * 1e6 * eps / (7850.0 * 650.0), rel=1e-12)
    m = with_adiabatic_heating(SeriesMember("c", eps, np.full(eps.size, sigma), 1.0, 600.0), density_kg_per_m3=7850.0,
                               heat_capacity_J_per_kg_K=650.0, beta=0.8)
    assert m.temperatures_at([0.4]) == pytest.approx(600.0 + 0.8 * sigma * 1e6 * 0.4 / (7850.0 * 650.0))
    assert m.temperature_rise_max_K == pytest.approx(0.8 * sigma * 1e6 * 0.8 / (7850.0 * 650.0))


def test_adiabatic_rise_against_the_heated_closed_form():
    """A record heated as it flows (β 0.9): the member's per-point temperatures within 0.5 K of the
    generator's own T(εp), from the measured curve."""
    rec, truth = hot_record(700.0, 0.1, beta=0.9)
    m = with_adiabatic_heating(member_from_record(rec, E_MPa=E_MPa), density_kg_per_m3=DENSITY_KG_PER_M3,
                               heat_capacity_J_per_kg_K=HEAT_CAPACITY_J_PER_KG_K)
    true_T = np.interp(m.plastic_strain, truth["eps_p"], truth["temperature_C"])
    assert true_T[-1] - 700.0 > 10.0  # the rise is there to find
    assert np.max(np.abs(m.point_temperatures_C - true_T)) < 0.5


def test_fit_adiabatic_states_the_rise_and_the_points_temperatures(tmp_path, capsys):
    """fit --adiabatic on a heated series: fit.json gives each record's largest rise, point_rates.csv each
    point's temperature, and the JC fit takes them (its error on the heated points is the isothermal fit's)."""
    paths = [write_record(tmp_path / f"{rec.source}.csv", rec) for rec in
             (hot_record(T, r, beta=0.9)[0] for T, r in FAST)]
    out = tmp_path / "fit"
    heat = ["--adiabatic", "--density", repr(DENSITY_KG_PER_M3), "--heat-capacity", repr(HEAT_CAPACITY_J_PER_KG_K)]
    assert main(["fit", *map(str, paths), "--out", str(out), *FIT, *heat]) == 0, capsys.readouterr().err
    d = json.loads((out / "fit.json").read_text())
    for rec in d["records"]:
        T, r = rec["temperature_C"], float(rec["name"].split("rate")[1])
        _, truth = hot_record(T, r, beta=0.9)
        assert rec["temperature_rise_max_K"] == pytest.approx(truth["temperature_C"][-1] - T, abs=0.5), rec["name"]
    table = pd.read_csv(out / d["point_rates_file"])
    for name, rows in table.groupby("record"):
        assert rows["temperature_C"].iloc[-1] > rows["temperature_C"].iloc[0] + 5.0, name
    assert any("adiabatic correction on 6 of 6 records" in w for w in d["warnings"])
    assert main(["fit", *map(str, paths), "--out", str(tmp_path / "no"), *FIT, "--adiabatic"]) == 2
    assert "--density" in capsys.readouterr().err


@pytest.mark.slow
def test_whole_hot_series_reads_in_fit(tmp_path, capsys):
    """The nine records of issue 45, the 0.001 1/s ones (35 000 samples at 50 Hz) too."""
    paths = _write(tmp_path, SERIES)
    out = tmp_path / "fit"
    assert main(["fit", *map(str, paths), "--out", str(out), *FIT]) == 0, capsys.readouterr().err
    assert len(json.loads((out / "fit.json").read_text())["records"]) == len(SERIES)


def test_jc_fit_on_heated_points_gives_the_isothermal_law(syn):
    """Johnson–Cook curves of 4340 heated as they flow (β 0.9, T = T0 + ΔT by fixed point): the global fit
    over each point's own temperature recovers the isothermal constants within 1 %; at the nominal
    temperatures it does not (the heating read as softening)."""
    from flowcurve.identification.series.series import fit_series

    rho, cp, beta = 7850.0, 470.0, 0.9
    members = []
    for T0 in (syn.REF["ref_temperature_C"], 300.0, 600.0):
        for rate in (1.0, 100.0):
            eps = np.linspace(0.002, 0.3, 40)
            T = np.full(eps.size, T0)
            for _ in range(40):  # the generator's own fixed point, independent of adiabatic_temperature_rise_K's quadrature
                sig = syn.true_stress(eps, rate, T)
                work = sig[0] * eps[0] + np.concatenate([[0.0], np.cumsum(0.5 * (sig[1:] + sig[:-1]) * np.diff(eps))])
                T = T0 + beta * work * 1e6 / (rho * cp)
            members.append(SeriesMember(f"T{T0:g}_{rate:g}", eps, sig, rate, T0))
    plain = fit_series([SeriesMember(m.name, m.plastic_strain, m.stress_MPa, m.strain_rate_per_s, m.temperature_C) for m in members],
                       **syn.REF).fit.params
    heated = fit_series([with_adiabatic_heating(m, density_kg_per_m3=rho, heat_capacity_J_per_kg_K=cp, beta=beta) for m in members],
                        **syn.REF).fit.params
    truth = syn.TRUE
    assert heated["A"] == pytest.approx(truth["A"], rel=0.01) and heated["B"] == pytest.approx(truth["B"], rel=0.01)
    assert heated["n"] == pytest.approx(truth["n"], rel=0.01) and heated["m"] == pytest.approx(truth["m"], rel=0.01)
    assert abs(plain["n"] / truth["n"] - 1.0) > 0.05 or abs(plain["B"] / truth["B"] - 1.0) > 0.05, plain


def test_a_regressed_window_without_loading_samples_falls_back_to_the_given_E(monkeypatch):
    """Issue 45's refusal "no sample of the first loading in the elastic window": with E given, a
    regressed line whose window (10–20 MPa, between the fast record's first two loaded samples)
    holds none of the first loading's samples stopped the record (and the whole series in fit).
    Now E is placed on the first loading, as for a record without a line: the same curve."""
    import flowcurve.identification.compression.identify as ci
    from flowcurve.identification.indicator import ModulusFit

    rec, _ = hot_record(800.0, 0.1)
    plain = member_from_record(rec, E_MPa=E_MPa)
    monkeypatch.setattr(ci, "elastic_line", lambda *a, **k: (ModulusFit(E_MPa, 1.0, 0.0, 0.9999, 3, (10.0, 20.0), source="test"), 0.0))
    m = member_from_record(rec, E_MPa=E_MPa)
    late = m.plastic_strain >= 0.02
    assert np.interp(m.plastic_strain[late], plain.plastic_strain, plain.stress_MPa) == pytest.approx(m.stress_MPa[late], rel=0.005)


def test_adiabatic_properties_from_the_record_header():
    """ρ and c_p from the record's material.density_kg_per_m3 / material.heat_capacity_J_per_kg_K when no
    option gives them; a record without them is named; --adiabatic-min-rate leaves the slow records isothermal."""
    from flowcurve.errors import IdentificationError
    from flowcurve.services.fit import FitRequest, adiabatic_heating

    rec, truth = hot_record(700.0, 0.1, beta=0.9)
    rec.meta.update({"material.density_kg_per_m3": repr(DENSITY_KG_PER_M3), "material.heat_capacity_J_per_kg_K": repr(HEAT_CAPACITY_J_PER_KG_K)})
    bare, _ = hot_record(800.0, 0.01, source="bare")
    fast, slow = member_from_record(rec, E_MPa=E_MPa), member_from_record(bare, E_MPa=E_MPa)
    with pytest.raises(IdentificationError, match="record.s. bare lack them"):
        adiabatic_heating(FitRequest([], adiabatic=True), [fast, slow])
    lines = adiabatic_heating(FitRequest([], adiabatic=True, adiabatic_min_rate=0.05), [fast, slow])
    assert "on 1 of 2 records" in lines[0] and slow.point_temperatures_C is None
    assert fast.temperature_rise_max_K == pytest.approx(truth["temperature_C"][-1] - 700.0, abs=0.5)
