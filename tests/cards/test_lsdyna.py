"""LS-DYNA cards read back by an independent parser (ansys-dyna-core's keyword reader)."""

import math
import warnings

import numpy as np
import pytest

from flowcurve.reports.cards import CardError, load_card_data, write_card

from .conftest import LAW, jc_MPa

dyna = pytest.importorskip("ansys.dyna.core", reason="ansys-dyna-core (the independent keyword reader) is not installed")

# Hand-worked factors from lab units (MPa, kg/m3, J/kgK, 1/s) into each system.
FACTORS = {
    "mm-s-t-N-MPa": dict(stress=1.0, density=1e-12, cp=1e6, rate=1.0),
    "mm-ms-kg-kN-GPa": dict(stress=1e-3, density=1e-9, cp=1.0, rate=1e-3),
    "m-s-kg-N-Pa": dict(stress=1e6, density=1.0, cp=1.0, rate=1.0),
    "mm-ms-g-N-MPa": dict(stress=1.0, density=1e-6, cp=1.0, rate=1e-3),
}


def read_deck(text):
    deck = dyna.Deck()
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # any field the reader cannot convert fails the test
        deck.loads(text)
    by_type = {}
    for kw in deck.keywords:
        by_type.setdefault(type(kw).__name__, []).append(kw)
    return deck, by_type


def close(a, b, rel=5e-5):
    """Equal to the precision of a 10-character field with one blank before the value
    (at least 5 significant digits)."""
    return math.isclose(float(a), float(b), rel_tol=rel, abs_tol=1e-300)


def assert_read_as_written(text, deck):
    """Every field under a '$#' name line reads back from ansys-dyna-core as exactly the
    number written at that position (10-character fields; 20 for curve points and table
    values), keyword by keyword in deck order."""
    keywords = iter(deck.keywords)
    lines = text.splitlines()
    current = None
    checked = 0
    for i, line in enumerate(lines):
        if line.startswith("*") and line not in ("*KEYWORD", "*END"):
            current = next(keywords)
        elif line.startswith("$#") and current is not None and i + 1 < len(lines) and lines[i + 1][:1] not in ("$", "*"):
            labels = line[2:].split()
            data = lines[i + 1]
            if labels in (["value"], ["a1", "o1"]):  # 20-character points up to the next keyword
                rows = []
                for row in lines[i + 1:]:
                    if row.startswith(("*", "$")):
                        break
                    rows.append([float(row[k:k + 20]) for k in range(0, len(row), 20)])
                read = (np.asarray(current.points.data, float)[:, None] if labels == ["value"]
                        else current.curves[["a1", "o1"]].to_numpy(float))
                np.testing.assert_array_equal(read, np.array(rows))
                checked += read.size
                continue
            for k, label in enumerate(labels):
                if not hasattr(current, label):
                    continue
                text_value = data[10 * k:10 * k + 10].strip()
                read = getattr(current, label)
                if text_value:
                    assert float(read) == float(text_value), (type(current).__name__, label, read, text_value)
                    checked += 1
    assert checked > 20


@pytest.mark.parametrize("units", sorted(FACTORS))
@pytest.mark.parametrize("options", [{}, {"id_offset": 70, "erosion_strain": 1.2}, {"curves": "law", "extend_to": 1.5},
                                     {"lsdyna_material": "224", "id_offset": 7, "erosion_strain": 1.2},
                                     {"lsdyna_material": "224", "curves": "law"}])
def test_every_field_reads_back_as_written(fit_file, units, options):
    path = fit_file(D1=0.05, D2=3.44, D3=-2.12, D4=0.002, D5=0.61, law=dict(LAW, rate0=1.0), rates=(1.0, 30.0))
    text = write_card(load_card_data(path), "lsdyna", units, **options)
    deck, _ = read_deck(text)
    assert_read_as_written(text, deck)


@pytest.mark.parametrize("units", sorted(FACTORS))
def test_johnson_cook_card_reads_back(fit_file, units):
    f = FACTORS[units]
    text = write_card(load_card_data(fit_file()), "lsdyna", units)
    assert text.startswith("*KEYWORD\n") and text.rstrip().endswith("*END")
    deck, kw = read_deck(text)
    assert_read_as_written(text, deck)
    jc = kw["MatJohnsonCook"][0]
    E, nu = 194000.0 * f["stress"], 0.25
    assert close(jc.ro, 7820.0 * f["density"])
    assert close(jc.e, E) and close(jc.pr, nu)
    assert close(jc.g, E / (2 * (1 + nu)))
    assert close(jc.a, LAW["A"] * f["stress"]) and close(jc.b, LAW["B"] * f["stress"])
    assert close(jc.n, LAW["n"]) and close(jc.c, LAW["C"]) and close(jc.m, LAW["m"])
    assert close(jc.tm, LAW["T_melt"] + 273.15) and close(jc.tr, LAW["T_ref"] + 273.15)
    assert close(jc.epso, LAW["rate0"] * f["rate"])
    assert close(jc.cp, 462.0 * f["cp"])
    assert jc.pc < -1e19  # no pressure cut-off
    assert jc.d1 >= 1e20 and (jc.d2, jc.d3, jc.d4, jc.d5) == (0, 0, 0, 0)  # no fracture identified: never fails
    eos = kw["EosLinearPolynomial"][0]
    assert close(eos.c1, E / (3 * (1 - 2 * nu)))  # bulk modulus
    assert eos.eosid == 1


@pytest.mark.parametrize("units", ["mm-s-t-N-MPa", "mm-ms-kg-kN-GPa"])
def test_piecewise_linear_table_over_log_rate(fit_file, units):
    f = FACTORS[units]
    text = write_card(load_card_data(fit_file()), "lsdyna", units)
    _, kw = read_deck(text)
    plp = kw["MatPiecewiseLinearPlasticity"][0]
    table = kw["DefineTable"][0]
    assert plp.lcss == table.tbid
    values = np.asarray(table.points.data)
    expected_rates = np.array([1e-3, 1e-2]) * f["rate"]
    np.testing.assert_allclose(values, np.log(expected_rates), rtol=1e-12)
    assert values[0] < 0  # LS-DYNA's signal that the values are ln(rate)
    curves = kw["DefineCurve"]
    assert len(curves) == 2
    for curve, rate in zip(curves, (1e-3, 1e-2)):
        eps = curve.curves["a1"].to_numpy()
        sig = curve.curves["o1"].to_numpy() / f["stress"]
        assert eps[0] == 0.0 and np.all(np.diff(eps) > 0)
        assert len(eps) <= 100
        # the measured curve was generated from the law: the card must follow it to within
        # resampling error, and start at the law's yield stress A·rate term
        np.testing.assert_allclose(sig[1:], jc_MPa(eps[1:], rate, 20.0), rtol=2e-3)
        assert sig[0] == pytest.approx(float(jc_MPa(0.0, rate, 20.0)), rel=1e-7)


def test_single_rate_gives_a_curve_and_a_contact_template(fit_file):
    text = write_card(load_card_data(fit_file(rates=(1e-3,))), "lsdyna", "mm-s-t-N-MPa")
    _, kw = read_deck(text)
    assert "DefineTable" not in kw
    plp = kw["MatPiecewiseLinearPlasticity"][0]
    (curve,) = kw["DefineCurve"]
    assert plp.lcss == curve.lcid
    assert not any("Contact" in name for name in kw)  # a template, not an active contact with SSID = MSID = 0
    # the template, activated as its comment says (IDs filled in), is a complete contact card
    lines = text.splitlines()
    start = lines.index("$*CONTACT_AUTOMATIC_SURFACE_TO_SURFACE")
    block = []
    for line in lines[start:]:
        if line.startswith("$*"):
            block.append(line[1:])
        elif line.startswith("$#"):
            block.append(line)
        elif line.startswith("$"):
            block.append(" " + line[1:])
        else:
            break
    active = "\n".join(block).replace("   <SURFA>", "         7").replace("   <SURFB>", "         8")
    _, contact_kw = read_deck("*KEYWORD\n" + active + "\n*END\n")
    contact = contact_kw["ContactAutomaticSurfaceToSurface"][0]
    assert (contact.surfa, contact.surfb) == (7, 8)
    assert close(contact.fs, 0.11) and close(contact.fd, 0.11)


def test_no_friction_no_contact_block(fit_file):
    text = write_card(load_card_data(fit_file(friction=None)), "lsdyna", "mm-s-t-N-MPa")
    _, kw = read_deck(text)
    assert not any("Contact" in name for name in kw)


def test_law_curves_when_the_fit_has_no_tables(fit_file):
    path = fit_file()
    data = load_card_data(path)
    data.curves = []
    text = write_card(data, "lsdyna", "mm-s-t-N-MPa")
    _, kw = read_deck(text)
    for curve, rate in zip(kw["DefineCurve"], (1e-3, 1e-2)):
        eps = curve.curves["a1"].to_numpy()
        np.testing.assert_allclose(curve.curves["o1"].to_numpy(), jc_MPa(eps, rate, 20.0), rtol=1e-7)
        assert eps[0] == 0.0 and eps[-1] == pytest.approx(2.0)  # the law to --extend-to (default 2)


def test_comment_block_states_units_range_sources_and_warning(fit_file):
    text = write_card(load_card_data(fit_file()), "lsdyna", "mm-ms-kg-kN-GPa")
    comments = " ".join(line[2:].strip() for line in text.splitlines() if line.startswith("$ "))
    for needle in ("mm-ms-kg-kN-GPa", "c20_v1", "c400_v1 (/lab/c400_v1.csv)", "method: global",
                   "plastic strain 0.002 to 0.25", "strain rate 0.001 to 0.01 1/s", "temperature 20 to 400",
                   "user's risk", "temperatures in K"):
        assert needle in comments, needle


def test_lines_stay_within_80_columns(fit_file):
    text = write_card(load_card_data(fit_file()), "lsdyna", "m-s-kg-N-Pa")
    for line in text.splitlines():
        assert len(line) <= 80, line


def test_identified_fracture_constants_are_written(fit_file):
    # table 3.2, 12Kh18N12M3TL
    path = fit_file(D1=0.0, D2=1.1, D3=-0.7, D4=-0.029, D5=-0.3)
    _, kw = read_deck(write_card(load_card_data(path), "lsdyna", "mm-s-t-N-MPa"))
    jc = kw["MatJohnsonCook"][0]
    assert (jc.d1, jc.d2, jc.d3, jc.d4, jc.d5) == (0.0, 1.1, -0.7, -0.029, -0.3)


def test_missing_constant_names_the_option(fit_file):
    path = fit_file(specific_heat_J_per_kgK=None)
    with pytest.raises(CardError, match="--cp"):
        write_card(load_card_data(path), "lsdyna", "mm-s-t-N-MPa")
    # given as an option it is used
    text = write_card(load_card_data(path, specific_heat_J_per_kgK=500.0), "lsdyna", "mm-s-t-N-MPa")
    _, kw = read_deck(text)
    assert close(kw["MatJohnsonCook"][0].cp, 5e8)
