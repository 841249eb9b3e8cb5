"""The rules every format shares (issue 12), each checked the way the solver reads the card:
temperature groups, ln-rate tables from eps_dot0, one extension rule, ID offset, ASCII,
fields kept apart."""

import math

import numpy as np
import pytest

from flowcurve.reports.cards import load_card_data, write_card

from .conftest import LAW, jc_MPa
from .readers import floats, read_inp
from .test_lsdyna import read_deck


def dyna_flow_stress(text, eps_p, rate_per_time_unit):
    """MAT_024's flow stress as LS-DYNA reads its LCSS: a *DEFINE_TABLE whose first value is
    negative holds ln(rate), otherwise rates; linear interpolation between the curves in
    that variable (end curves beyond the ends), each curve linear in plastic strain."""
    _, kw = read_deck(text)
    plp = kw["MatPiecewiseLinearPlasticity"][0]
    curves = {c.lcid: c.curves for c in kw["DefineCurve"]}
    if "DefineTable" not in kw:
        c = curves[plp.lcss]
        return np.interp(eps_p, c["a1"], c["o1"])
    table = kw["DefineTable"][0]
    assert plp.lcss == table.tbid
    values = np.asarray(table.points.data, float)
    x = math.log(rate_per_time_unit) if values[0] < 0 else rate_per_time_unit
    ids = sorted(curves)  # the curves follow the table in order
    stresses = np.array([np.interp(eps_p, curves[i]["a1"], curves[i]["o1"]) for i in ids])
    return np.array([np.interp(x, values, stresses[:, k]) for k in range(stresses.shape[1])])


def plastic_blocks(text, table_material=None):
    """{temperature: rows (stress, strain)} of the *PLASTIC table (Abaqus: of the _TABLE material)."""
    blocks = read_inp(text)
    rows = None
    for key, opts, data in blocks:
        if key == "MATERIAL":
            current = opts["NAME"]
        if key == "PLASTIC" and not opts and (table_material is None or current.endswith(table_material)):
            rows = floats(data)
    return {t: rows[rows[:, 2] == t][:, :2] for t in sorted(set(rows[:, 2]))}


# -- temperatures within a tolerance are one ------------------------------------------------------------------
def test_two_records_a_few_millikelvin_apart_are_one_temperature(fit_file):
    path = fit_file(conditions=[(19.9934, 1e-3), (19.9957, 1e-2)])
    data = load_card_data(path)
    text = write_card(data, "lsdyna", "mm-s-t-N-MPa")
    _, kw = read_deck(text)
    assert "DefineTable" in kw and len(kw["DefineTable"][0].points.data) == 2  # rate-dependent: both curves kept
    for rate in (1e-3, 1e-2):
        eps = np.array([0.05, 0.2])
        np.testing.assert_allclose(dyna_flow_stress(text, eps, rate), jc_MPa(eps, rate, 20.0), rtol=2e-3)
    for fmt, name in (("abaqus", "_TABLE"), ("calculix", None)):
        blocks = plastic_blocks(write_card(data, fmt, "mm-s-t-N-MPa"), name)
        assert len(blocks) == 1 and list(blocks)[0] == pytest.approx(19.99455)
        assert blocks[list(blocks)[0]][-1, 1] == pytest.approx(2.0)  # not cut at the shorter curve's end
    # a tolerance below their distance keeps them apart
    apart = plastic_blocks(write_card(data, "calculix", "mm-s-t-N-MPa", temperature_tolerance_C=1e-3))
    assert len(apart) == 2


# -- ln-rate tables: eps_dot0 included, the same interpolation in every unit system ---------------------------
@pytest.mark.parametrize("source", ["measured", "law"])
def test_rate_table_reads_the_same_in_s_and_ms_decks(fit_file, source):
    law = dict(LAW, rate0=1.0)  # eps_dot0 = 1/s: ln(rate per s) >= 0 for every tested rate
    data = load_card_data(fit_file(law=law, temperatures=(20.0,), rates=(1.0, 10.0, 100.0)))
    eps = np.array([0.01, 0.1, 0.2])
    seconds = write_card(data, "lsdyna", "mm-s-t-N-MPa", curves=source)
    millis = write_card(data, "lsdyna", "mm-ms-kg-kN-GPa", curves=source)
    for rate in (0.5, 1.0, 3.0, 30.0, 100.0):  # 1/s
        s = dyna_flow_stress(seconds, eps, rate)
        ms = dyna_flow_stress(millis, eps, rate * 1e-3) * 1e3  # GPa -> MPa
        np.testing.assert_allclose(ms, s, rtol=1e-6)
        # linear in ln(rate) is the law's own rate factor: exact between the rows
        np.testing.assert_allclose(s, jc_MPa(eps, rate, 20.0, law), rtol=2e-3)


def test_law_table_holds_the_bend_at_eps_dot0(fit_file):
    # rates tested 1e-4 .. 1e-1 with eps_dot0 = 1e-3 inside: no rate effect below, ln above
    data = load_card_data(fit_file(temperatures=(20.0,), rates=(1e-4, 1e-1)))
    text = write_card(data, "lsdyna", "mm-s-t-N-MPa", curves="law")
    _, kw = read_deck(text)
    assert np.asarray(kw["DefineTable"][0].points.data) == pytest.approx(np.log([1e-3, 1e-1]), rel=1e-9)
    eps = kw["DefineCurve"][0].curves["a1"].to_numpy()[[5, 20, 40]]  # on the tabulated points: no strain interpolation
    for rate in (1e-4, 1e-3, 1e-2, 1e-1):  # a row at 1e-4 and 1e-1 only would be 1.5 % high at 1e-3
        np.testing.assert_allclose(dyna_flow_stress(text, eps, rate), jc_MPa(eps, rate, 20.0), rtol=1e-7)


# -- one rule beyond the last measured point, in every format ---------------------------------------------------
def test_every_format_extends_the_same_way(fit_file):
    def noisy(e, r, T):  # measured data that bends up at its end, as a noisy neck does
        return jc_MPa(e, r, T) * (1.0 + 0.05 * (e / 0.25) ** 8)

    data = load_card_data(fit_file(temperatures=(20.0,), rates=(1e-3,), curve=noisy))
    last = float(noisy(0.25, 1e-3, 20.0))
    static = lambda e: LAW["A"] + LAW["B"] * e ** LAW["n"]  # noqa: E731
    probe = np.array([0.5, 1.0, 2.0])
    expected = last * static(probe) / static(0.25)  # the fitted hardening through the last point
    dyna = dyna_flow_stress(write_card(data, "lsdyna", "mm-s-t-N-MPa"), probe, 1e-3)
    (abaqus,) = plastic_blocks(write_card(data, "abaqus", "mm-s-t-N-MPa"), "_TABLE").values()
    (calculix,) = plastic_blocks(write_card(data, "calculix", "mm-s-t-N-MPa")).values()
    for table in (abaqus, calculix):
        assert table[-1, 1] == pytest.approx(2.0)
        np.testing.assert_allclose(np.interp(probe, table[:, 1], table[:, 0]), dyna, rtol=1e-6)
    np.testing.assert_allclose(dyna, expected, rtol=5e-3)  # piecewise-linear between 10 log-spaced rows
    # not the last slope of the data: that would give far more at eps_p 0.5
    measured = np.linspace(0.002, 0.25, 300)
    slope = np.polyfit(measured[-3:], noisy(measured[-3:], 1e-3, 20.0), 1)[0]
    assert last + slope * 0.25 > 1.1 * dyna[0]
    # --extend-to moves the end in every format
    short = plastic_blocks(write_card(data, "calculix", "mm-s-t-N-MPa", extend_to=0.8))
    assert list(short.values())[0][-1, 1] == pytest.approx(0.8)


# -- IDs, ASCII, fields apart -------------------------------------------------------------------------------------
def test_id_offset_moves_every_lsdyna_id(fit_file):
    plain = read_deck(write_card(load_card_data(fit_file()), "lsdyna", "mm-s-t-N-MPa"))[1]
    moved = read_deck(write_card(load_card_data(fit_file()), "lsdyna", "mm-s-t-N-MPa", id_offset=1000,
                                 erosion_strain=1.5))[1]

    def ids(kw):
        return {"mid": sorted(k.mid for name in ("MatJohnsonCook", "MatPiecewiseLinearPlasticity") for k in kw[name]),
                "eosid": [k.eosid for k in kw["EosLinearPolynomial"]], "tbid": [k.tbid for k in kw["DefineTable"]],
                "lcid": [k.lcid for k in kw["DefineCurve"]], "lcss": [k.lcss for k in kw["MatPiecewiseLinearPlasticity"]]}

    before, after = ids(plain), ids(moved)
    for key in before:
        assert after[key] == [v + 1000 for v in before[key]], key
    assert sorted(k.mid for k in moved["MatAddErosion"]) == after["mid"]
    assert all(k.effeps == 1.5 for k in moved["MatAddErosion"])


@pytest.mark.parametrize("fmt", ["lsdyna", "abaqus", "radioss", "calculix"])
def test_cards_are_plain_ascii(fit_file, fmt):
    data = load_card_data(fit_file(material="12Х18Н12М3ТЛ °C ±", D1=0.0, D2=1.3, D3=-0.17, D4=0.063, D5=2.8))
    data.warnings.append("σ ≤ 3 % at 20 °C, ε̇ = 1e-3 1/s")
    write_card(data, fmt, "mm-s-t-N-MPa").encode("ascii")


def test_no_two_values_run_together(fit_file):
    text = write_card(load_card_data(fit_file()), "lsdyna", "m-s-kg-N-Pa")
    width = 10
    for line in text.splitlines():
        if line.startswith("$#"):
            width = 20 if line.split() in (["$#", "value"], ["$#", "a1", "o1"]) else 10
            continue
        if line.startswith(("$", "*")) or not line.strip():
            continue
        for k in range(0, len(line), width):
            field = line[k:k + width]
            assert field.strip() == "" or field[0] == " ", line


def test_demo_like_series_gives_a_rate_dependent_mat024_and_one_temperature_block(tmp_path):
    """Two tests at two rates, one temperature that the thermocouple read as 19.9934 and
    19.9957 C: through 'flowcurve fit' (its files) to the cards."""
    from flowcurve.services.fit import write_fit
    from flowcurve.identification.series.series import SeriesMember, fit_series

    eps = np.linspace(0.002, 0.12, 60)
    members = [SeriesMember(name=f"t{i}", plastic_strain=eps, stress_MPa=jc_MPa(eps, rate, 20.0), strain_rate_per_s=rate,
                            temperature_C=temp, test="tension")
               for i, (temp, rate) in enumerate(((19.9934, 1e-3), (19.9957, 1e-2)))]
    series = fit_series(members, ref_strain_rate_per_s=1e-3, ref_temperature_C=19.9934, melt_temperature_C=1400.0,
                        fixed={"m": LAW["m"]})
    fit_path = write_fit(series, tmp_path / "fit")
    data = load_card_data(fit_path, E_MPa=194000.0, poisson=0.25, density_kg_per_m3=7820.0, specific_heat_J_per_kgK=462.0)
    text = write_card(data, "lsdyna", "mm-s-t-N-MPa")
    _, kw = read_deck(text)
    assert np.asarray(kw["DefineTable"][0].points.data) == pytest.approx(np.log([1e-3, 1e-2]))  # rate-dependent
    probe = np.array([0.05, 0.1])
    np.testing.assert_allclose(dyna_flow_stress(text, probe, 1e-2), jc_MPa(probe, 1e-2, 20.0), rtol=3e-3)
    for fmt, name in (("abaqus", "_TABLE"), ("calculix", None)):
        blocks = plastic_blocks(write_card(data, fmt, "mm-s-t-N-MPa"), name)
        assert len(blocks) == 1  # one temperature block
        (rows,) = blocks.values()
        assert rows[-1, 1] == pytest.approx(2.0)  # not cut at 0.12: the stated extension
