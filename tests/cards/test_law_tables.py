"""Tables from any registered law (issue 45): LS-DYNA *MAT_224 read back by ansys-dyna-core and
evaluated by this file's own reader, the flow-stress CSV read back with the csv module, and a
law other than Johnson–Cook (a toy law registered here) through *MAT_024 and the Abaqus table.
The truth is ``get_law(...).stress`` (or this file's toy law), never the writers' code."""

import csv
import io
import json
import math
import warnings

import numpy as np
import pytest

from flowcurve.cli import main
from flowcurve.identification.laws import base
from flowcurve.identification.laws.base import Law, Parameter, get_law
from flowcurve.reports.cards import CardError, load_card_data, write_card

from .conftest import LAW, make_fit
from .readers import floats, read_inp

dyna = pytest.importorskip("ansys.dyna.core", reason="ansys-dyna-core (the independent keyword reader) is not installed")

JC_VALUES = dict(A=LAW["A"], B=LAW["B"], n=LAW["n"], C=LAW["C"], m=LAW["m"], ref_strain_rate_per_s=LAW["rate0"],
                 ref_temperature_C=LAW["T_ref"], melt_temperature_C=LAW["T_melt"])
TEMPS_C = (20.0, 300.0, 600.0)
RATES = (1e-3, 1e-2, 1e-1)
EPS = np.array([0.02, 0.05, 0.1, 0.2, 0.25, 0.5])
# mm-ms-kg-kN-GPa: stress in GPa (1e-3 MPa), rate per ms (1e-3 per s)
STRESS_PER_MPA, RATE_PER_S = 1e-3, 1e-3


def jc_truth(eps, rate, T):
    return get_law("johnson_cook").stress(eps, rate, T, **JC_VALUES)


# -- an independent reader of LS-DYNA tables --------------------------------------------------
def deck_keywords(text):
    deck = dyna.Deck()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        deck.loads(text)
    return list(deck.keywords)


def tables_of(keywords):
    """{table id: (values, [(strain, stress) per curve])}: the curves that follow a *DEFINE_TABLE, in order."""
    out = {}
    for i, kw in enumerate(keywords):
        if type(kw).__name__ == "DefineTable":
            values = np.asarray(kw.points.data, float).ravel()
            curves = [keywords[i + 1 + k] for k in range(values.size)]
            assert all(type(c).__name__ == "DefineCurve" for c in curves)
            out[kw.tbid] = (values, [(c.curves["a1"].to_numpy(float), c.curves["o1"].to_numpy(float)) for c in curves])
    return out


def table_at(table, x, eps):
    """Stress at ``eps`` interpolated linearly between the table's curves at value ``x`` (held at the ends)."""
    values, curves = table
    at = np.array([np.interp(eps, e, s) for e, s in curves])
    return np.array([np.interp(x, values, at[:, k]) for k in range(at.shape[1])])


def mat224_stress(text, eps, rate_per_s, T_C):
    """MAT_224's yield as the keyword manual defines it: k1(eps, rate) kt(eps, T)/kt(eps, TR),
    k1 over ln(rate) (the table's first value negative), kt over T in K."""
    keywords = deck_keywords(text)
    (mat,) = [k for k in keywords if type(k).__name__ == "MatTabulatedJohnsonCook"]
    tables = tables_of(keywords)
    k1, kt = tables[mat.tabk1], tables[mat.tabkt]
    assert k1[0][0] < 0  # ln(rate)
    k = table_at(k1, math.log(rate_per_s * RATE_PER_S), eps)
    return k * table_at(kt, T_C + 273.15, eps) / table_at(kt, mat.tr, eps) / STRESS_PER_MPA


@pytest.fixture
def series(tmp_path):
    path = tmp_path / "fit" / "fit.json"
    path.parent.mkdir()
    path.write_text(json.dumps(make_fit(path.parent, temperatures=TEMPS_C, rates=RATES)), encoding="utf-8")
    return path


@pytest.mark.parametrize("curves, temps, rates", [
    ("auto", TEMPS_C, (1e-3, 3e-3, 1e-1)),  # measured curves at the tested temperatures; 3e-3 between rows
    ("law", (20.0, 450.0, 600.0), (2e-3, 1e-2, 5e-2)),  # the law: 450 C and two rates between rows
])
def test_mat224_reads_back_and_equals_the_law(series, tmp_path, curves, temps, rates):
    out = tmp_path / "mat224.k"
    assert main(["card", str(series), "--format", "lsdyna", "--lsdyna-material", "224", "--units", "mm-ms-kg-kN-GPa",
                 "--curves", curves, "-o", str(out)]) == 0
    text = out.read_text()
    assert "*MAT_TABULATED_JOHNSON_COOK" in text and "*DEFINE_TABLE" in text and "*MAT_JOHNSON_COOK\n" not in text
    keywords = deck_keywords(text)
    (mat,) = [k for k in keywords if type(k).__name__ == "MatTabulatedJohnsonCook"]
    assert mat.tr == pytest.approx(293.15) and mat.e == pytest.approx(194000.0 * STRESS_PER_MPA)
    for T in temps:
        for rate in rates:
            np.testing.assert_allclose(mat224_stress(text, EPS, rate, T), jc_truth(EPS, rate, T), rtol=5e-3,
                                       err_msg=f"{T} C, {rate} 1/s")
    # the rule stated: clamped beyond the tabulated range (no rate effect beyond the fastest row)
    comments = " ".join(line[2:].strip() for line in text.splitlines() if line.startswith("$ "))
    assert "clamped to the tabulated" in comments and "misses the law by up to 0 %" in comments


def read_flow_table(text):
    header = [line for line in text.splitlines() if line.startswith("#")]
    rows = list(csv.DictReader(io.StringIO("\n".join(line for line in text.splitlines() if not line.startswith("#")))))
    return header, rows


@pytest.mark.parametrize("curves, rtol", [("law", 1e-3), ("measured", 5e-3)])
def test_flow_table_holds_every_measured_condition_and_the_law(series, tmp_path, curves, rtol):
    out = tmp_path / "flow.csv"
    assert main(["card", str(series), "--format", "flow-table", "--curves", curves, "-o", str(out)]) == 0
    header, rows = read_flow_table(out.read_text())
    assert list(rows[0]) == ["eps_p", "strain_rate_per_s", "temperature_C", "stress_MPa"]
    fit = json.loads(series.read_text())
    conditions = {(float(r["temperature_C"]), float(r["strain_rate_per_s"])) for r in rows}
    for c in fit["curves"]:
        assert (c["temperature_C"], c["strain_rate_per_s"]) in conditions
    eps, rate, T, sig = (np.array([float(r[k]) for r in rows]) for k in ("eps_p", "strain_rate_per_s", "temperature_C", "stress_MPa"))
    check = eps >= 0.002 if curves == "measured" else eps >= 0.0
    np.testing.assert_allclose(sig[check], jc_truth(eps[check], rate[check], T[check]), rtol=rtol)
    text = " ".join(header)
    for needle in ("johnson_cook", "A_MPa = 105", "melt_temperature_C = 1400", "temperature unit: C",
                   "plastic strain 0.002 to 0.25", "rule:", "clamp"):
        assert needle in text, needle


# -- a law other than Johnson–Cook ---------------------------------------------------------------
class ToyTablesLaw(Law):
    """σ = K εp^n (ε̇/ε̇0)^q exp(−β (T − 20)) with a strain-dependent rate exponent q = q0 (1 + εp):
    not separable, not linear in ln ε̇ — the tables must carry it anyway."""

    name = "toy_tables_law"
    display_name = "Toy (tables test)"
    parameters = (Parameter("K", "K_MPa", "MPa", 0.0), Parameter("n", "n", "", 0.0, 1.0), Parameter("q0", "q0", "", 0.0, 1.0),
                  Parameter("beta", "beta_per_K", "1/K", 0.0))
    conditions = (Parameter("ref_strain_rate_per_s", "ref_strain_rate_per_s", "1/s", 0.0),)
    rate_dependent = True
    temperature_dependent = True
    equation = "K*(eps_p+0.01)^n*(rate/ref_rate)^(q0*(1+eps_p))*exp(-beta*(T-20))"
    latex = r"K(\varepsilon_p+0.01)^n(\dot\varepsilon/\dot\varepsilon_0)^{q_0(1+\varepsilon_p)}e^{-\beta(T-20)}"
    source = "a test-local law (tests/cards/test_law_tables.py)"

    def evaluate(self, eps_p, strain_rate_per_s, temperature_C, *, K, n, q0, beta, ref_strain_rate_per_s):
        return (K * (eps_p + 0.01) ** n * (strain_rate_per_s / ref_strain_rate_per_s) ** (q0 * (1 + eps_p))
                * np.exp(-beta * (temperature_C - 20.0)))

    def guess(self, eps_p, stress_MPa, strain_rate_per_s=None, temperature_C=None, **conditions):
        return {"K": 500.0, "n": 0.2, "q0": 0.05, "beta": 1e-3}


TOY = dict(K=600.0, n=0.25, q0=0.08, beta=1.5e-3, ref_strain_rate_per_s=1e-3)


def toy_truth(eps, rate, T):
    return get_law("toy_tables_law").stress(eps, rate, T, **TOY)


@pytest.fixture(autouse=True)
def toy_laws(monkeypatch):
    """The test's laws registered for this file's tests only (the registry of every other test stays the product's)."""
    base.registered_laws()  # discover the product's laws first
    for cls in (ToyTablesLaw, ToyNonSeparableLaw):
        monkeypatch.setitem(base._REGISTRY, cls.name, cls())


@pytest.fixture
def toy_series(tmp_path):
    path = tmp_path / "toy" / "fit.json"
    path.parent.mkdir()
    fit = make_fit(path.parent, temperatures=(20.0, 300.0), rates=(1e-3, 1e-1), curve=toy_truth)
    for key in ("A_MPa", "B_MPa", "n", "C", "m", "A_MPa_stderr", "B_MPa_stderr", "n_stderr"):
        fit.pop(key)
    for c in fit["curves"]:
        c["model_stress_at_zero_strain_MPa"] = float(toy_truth(0.0, c["strain_rate_per_s"], c["temperature_C"]))
    law = get_law("toy_tables_law")
    fit.update(schema="flowcurve-fit/2", model="toy_tables_law", ref_strain_rate_per_s=1e-3,
               law={"name": law.name, "display_name": law.display_name, "equation": law.equation,
                    "parameters": {p.key: TOY[p.name] for p in law.parameters}, "stderr": {p.key: None for p in law.parameters},
                    "conditions": {"ref_strain_rate_per_s": 1e-3}, "temperature_unit": "C"})
    path.write_text(json.dumps(fit), encoding="utf-8")
    return path


@pytest.mark.parametrize("curves", ["law", "measured"])
def test_another_law_through_mat024(toy_series, curves):
    text = write_card(load_card_data(toy_series), "lsdyna", "mm-ms-kg-kN-GPa", lsdyna_material="24", curves=curves)
    keywords = deck_keywords(text)
    assert [type(k).__name__ for k in keywords].count("MatPiecewiseLinearPlasticity") == 1
    assert "MatJohnsonCook" not in {type(k).__name__ for k in keywords}
    (table,) = tables_of(keywords).values()
    # a rate between the tested 1e-3 and 1e-1 1/s: the law table has rows where the law bends; measured curves
    # only at the tested rates, so only those are claimed for them
    rates = (1e-3, 1e-2, 1e-1) if curves == "law" else (1e-3, 1e-1)
    for rate in rates:
        got = table_at(table, math.log(rate * RATE_PER_S), EPS) / STRESS_PER_MPA
        np.testing.assert_allclose(got, toy_truth(EPS, rate, 20.0), rtol=5e-3, err_msg=f"{rate} 1/s")
    assert "Toy (tables test)" in text


def test_another_law_through_the_abaqus_table(toy_series):
    text = write_card(load_card_data(toy_series), "abaqus", "mm-s-t-N-MPa", curves="law", strain_rate_per_s=1e-2)
    blocks = read_inp(text)
    names = [opts["NAME"] for k, opts, _ in blocks if k == "MATERIAL"]
    assert names == ["12KH18N12M3TL_TABLE"]  # no Johnson-Cook material for another law
    rows = floats(next(rows for k, opts, rows in blocks if k == "PLASTIC" and not opts))
    stress, eps, T = rows.T
    assert set(T) == {20.0, 300.0}
    np.testing.assert_allclose(stress, toy_truth(eps, 1e-2, T), rtol=1e-6)


@pytest.mark.parametrize("fmt, options", [("radioss", {}), ("lsdyna", {}), ("lsdyna", {"lsdyna_material": "15"})])
def test_johnson_cook_only_formats_refuse_another_law_in_one_line(toy_series, fmt, options):
    with pytest.raises(CardError) as err:
        write_card(load_card_data(toy_series), fmt, "mm-s-t-N-MPa", **options)
    message = str(err.value)
    assert "\n" not in message and "Toy (tables test)" in message
    for able in ("224", "flow-table", "abaqus"):
        assert able in message


def test_another_law_through_mat224_and_the_flow_table(toy_series, tmp_path):
    text = write_card(load_card_data(toy_series), "lsdyna", "mm-ms-kg-kN-GPa", lsdyna_material="224", curves="law")
    for T in (20.0, 300.0):
        for rate in (1e-3, 1e-1):  # the toy law's temperature term is a factor: MAT_224's k1 kt/kt(TR) is exact for it
            np.testing.assert_allclose(mat224_stress(text, EPS, rate, T), toy_truth(EPS, rate, T), rtol=5e-3)
    _, rows = read_flow_table(write_card(load_card_data(toy_series), "flow-table", "mm-s-t-N-MPa", curves="law"))
    eps, rate, T, sig = (np.array([float(r[k]) for r in rows]) for k in ("eps_p", "strain_rate_per_s", "temperature_C", "stress_MPa"))
    np.testing.assert_allclose(sig, toy_truth(eps, rate, T), rtol=1e-6)


class ToyNonSeparableLaw(ToyTablesLaw):
    """The toy law with a rate exponent that grows with temperature: MAT_224's product form cannot carry it exactly."""

    name = "toy_nonseparable_law"
    display_name = "Toy non-separable (tables test)"

    def evaluate(self, eps_p, strain_rate_per_s, temperature_C, *, K, n, q0, beta, ref_strain_rate_per_s):
        q = q0 * (1 + eps_p) * (1 + (temperature_C - 20.0) / 300.0)
        return K * (eps_p + 0.01) ** n * (strain_rate_per_s / ref_strain_rate_per_s) ** q * np.exp(-beta * (temperature_C - 20.0))


def test_mat224_states_how_far_its_product_form_misses_a_law(toy_series, tmp_path):
    """A law whose rate effect depends on temperature: the card states a miss at least as large as this file's
    reader finds at the hot, fast tested condition (Johnson–Cook's 0 % is checked with the JC card above)."""
    fit = json.loads(toy_series.read_text())
    fit["law"]["name"] = fit["model"] = "toy_nonseparable_law"
    path = tmp_path / "toy" / "fit_nonsep.json"
    path.write_text(json.dumps(fit), encoding="utf-8")
    text = write_card(load_card_data(path), "lsdyna", "mm-ms-kg-kN-GPa", lsdyna_material="224", curves="law")
    comments = " ".join(line[2:].strip() for line in text.splitlines() if line.startswith("$ "))
    stated = float(comments.split("misses the law by up to ")[1].split(" %")[0]) / 100
    truth = get_law("toy_nonseparable_law").stress(EPS, 1e-1, 300.0, **TOY)
    found = float(np.max(np.abs(mat224_stress(text, EPS, 1e-1, 300.0) / truth - 1)))
    assert found > 0.01  # the form does miss this law
    assert stated >= 0.9 * found and "flow-table" in comments


@pytest.mark.slow
@pytest.mark.solver
@pytest.mark.skipif(__import__("shutil").which("ccx") is None, reason="CalculiX 'ccx' is not installed")
def test_one_element_in_ccx_carries_another_law(toy_series, tmp_path):
    """The CalculiX temperature table of the test-local law at 1e-2 1/s: a one-element compression at 300 C in
    ccx follows that law (not the card's rows: the law itself) within 0.5 % from eps_p 0.002."""
    import os
    import subprocess

    from .readers import read_dat
    from .test_calculix import ONE_ELEMENT

    text = write_card(load_card_data(toy_series), "calculix", "mm-s-t-N-MPa", curves="law", strain_rate_per_s=1e-2)
    (tmp_path / "job.inp").write_text(ONE_ELEMENT.format(material=text, name="12KH18N12M3TL", temperature=300.0))
    run = subprocess.run(["ccx", "-i", "job"], cwd=tmp_path, capture_output=True, text=True, timeout=120,
                         env={**os.environ, "OMP_NUM_THREADS": "1"})
    assert "*ERROR" not in run.stdout + run.stderr, run.stdout[-2000:]
    dat = read_dat((tmp_path / "job.dat").read_text())
    checked = 0
    for (t, s), (_, p) in zip(dat["stresses"], dat["equivalent plastic strain"]):
        eps_p = p[:, 2].mean()
        if eps_p < 0.002:
            continue
        assert -s[:, 4].mean() == pytest.approx(float(toy_truth(eps_p, 1e-2, 300.0)), rel=5e-3), (t, eps_p)
        checked += 1
    assert checked >= 30


def test_a_hensel_spittel_fit_through_the_flow_table_and_mat224(tmp_path):
    """Once seriesfit's Hensel–Spittel is registered: a 700/800/900 C x 0.001/0.01/0.1 1/s series of it, the flow
    table within 0.1 % of the law at the nine conditions over eps_p 0.05-0.6 (from the law and from the curves), and
    MAT_224's stated miss of its product form (HS's m8 couples rate and temperature) at least what the reader finds."""
    if "hensel_spittel" not in base.registered_laws():
        pytest.skip("Hensel–Spittel is not registered on this branch (seriesfit's module)")
    hs = get_law("hensel_spittel")
    values = dict(A=3500.0, m1=-0.0032, m2=0.18, m3=0.12, m4=-0.004, m5=0.0, m7=-0.3, m8=0.0002, m9=0.0)

    def truth(e, r, T):
        return hs.stress(e, r, T, **values)

    folder = tmp_path / "hs"
    folder.mkdir()
    fit = make_fit(folder, temperatures=(700.0, 800.0, 900.0), rates=RATES, curve=truth, last_strain=0.6)
    for key in ("A_MPa", "B_MPa", "n", "C", "m", "A_MPa_stderr", "B_MPa_stderr", "n_stderr"):
        fit.pop(key)
    for c in fit["curves"]:
        c["model_stress_at_zero_strain_MPa"] = float(truth(0.0, c["strain_rate_per_s"], c["temperature_C"]))
    fit.update(schema="flowcurve-fit/2", model="hensel_spittel",
               law={"name": hs.name, "display_name": hs.display_name, "equation": hs.equation, "parameters": hs.to_keys(values),
                    "stderr": {}, "conditions": {}, "temperature_unit": "C"})
    (folder / "fit.json").write_text(json.dumps(fit), encoding="utf-8")
    data = load_card_data(folder / "fit.json")
    for curves in ("law", "measured"):
        _, rows = read_flow_table(write_card(data, "flow-table", "mm-s-t-N-MPa", curves=curves))
        eps, rate, T, sig = (np.array([float(r[k]) for r in rows]) for k in ("eps_p", "strain_rate_per_s", "temperature_C", "stress_MPa"))
        assert len(set(zip(rate, T))) == 9
        band = (eps >= 0.05) & (eps <= 0.6)
        np.testing.assert_allclose(sig[band], truth(eps[band], rate[band], T[band]), rtol=1e-3)
    text = write_card(data, "lsdyna", "mm-ms-kg-kN-GPa", lsdyna_material="224", curves="law")
    comments = " ".join(line[2:].strip() for line in text.splitlines() if line.startswith("$ "))
    stated = float(comments.split("misses the law by up to ")[1].split(" %")[0]) / 100
    found = float(np.max(np.abs(mat224_stress(text, EPS, 1e-1, 900.0) / truth(EPS, 1e-1, 900.0) - 1)))
    assert stated >= 0.9 * found
