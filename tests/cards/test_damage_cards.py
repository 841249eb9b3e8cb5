"""D1-D5 in the three solvers' cards, read at each solver's field positions: LS-DYNA by
ansys-dyna-core, Abaqus by the keyword reference's data-line order, OpenRadioss by the CARD
formats of its fail_johnson.cfg."""

import math

import pytest

from flowcurve.identification.series.damage import fracture_strain

from flowcurve.reports.cards import load_card_data, write_card

from .conftest import LAW
from .readers import floats, read_inp, read_radioss, read_radioss_block
from .test_lsdyna import read_deck

STEEL45 = dict(D1=0.0, D2=1.3, D3=-0.17, D4=0.063, D5=2.8)  # docs/methods.md §5, table 3.2
ERRORS = dict(D1_stderr=None, D2_stderr=0.013, D3_stderr=0.007, D4_stderr=0.0011, D5_stderr=0.045)


def damage_fit(fit_file):
    return fit_file(**STEEL45, **ERRORS, damage={"triaxiality_range": [1 / 3, 1.72]})


def test_lsdyna_mat015_holds_d1_to_d5(fit_file):
    _, kw = read_deck(write_card(load_card_data(damage_fit(fit_file)), "lsdyna", "mm-s-t-N-MPa"))
    jc = kw["MatJohnsonCook"][0]
    assert (jc.d1, jc.d2, jc.d3, jc.d4, jc.d5) == tuple(STEEL45.values())
    assert jc.epso == LAW["rate0"]  # the reference rate of D4 is the flow law's


@pytest.mark.parametrize("displacement", [None, 0.05])
def test_abaqus_damage_initiation_and_the_users_evolution(fit_file, displacement):
    text = write_card(load_card_data(damage_fit(fit_file)), "abaqus", "m-s-kg-N-Pa", damage_displacement_mm=displacement)
    blocks = read_inp(text)
    inits = [i for i, (k, _, _) in enumerate(blocks) if k == "DAMAGE INITIATION"]
    assert len(inits) == 2  # both materials
    for i in inits:
        key, opts, rows = blocks[i]
        assert opts == {"CRITERION": "JOHNSON COOK"}
        # keyword reference: d1, d2, d3, d4, d5, melting temperature, transition temperature, reference strain rate
        d1, d2, d3, d4, d5, t_melt, t_trans, eps0 = floats(rows)[0]
        assert (d1, d2, d3, d4, d5) == (STEEL45["D1"], STEEL45["D2"], -STEEL45["D3"], STEEL45["D4"], STEEL45["D5"])
        assert (t_melt, t_trans, eps0) == (LAW["T_melt"], LAW["T_ref"], LAW["rate0"])
        following = blocks[i + 1] if i + 1 < len(blocks) else None
        if displacement is None:
            assert following is None or following[0] != "DAMAGE EVOLUTION"
        else:
            assert following[0] == "DAMAGE EVOLUTION"
            assert following[1] == {"TYPE": "DISPLACEMENT", "SOFTENING": "LINEAR"}
            assert floats(following[2])[0, 0] == pytest.approx(5e-5)  # 0.05 mm in m
    assert "p/q" in text and "d3 = -D3" in text and ("output only" in text) == (displacement is None)


def abaqus_failure_strain(d1, d2, d3, p_over_q):
    """Abaqus' Johnson-Cook failure strain at the reference rate and temperature, as its manual writes it:
    d1 + d2·exp(d3·p/q), p the pressure stress (positive in compression), q the Mises stress."""
    return d1 + d2 * math.exp(d3 * p_over_q)


@pytest.mark.parametrize("eta", [1 / 3, 0.6])
def test_abaqus_cards_own_formula_gives_the_fitted_locus(fit_file, eta):
    """Parse the card back and evaluate Abaqus' formula with its d1-d3 at triaxiality η (p/q = −η): the fitted
    locus D1 + D2·exp(D3·η) of steel 45 (D3 = −0.17, the fracture strain falling with η), both η of the card's range.
    Copied unchanged, d3 = −0.17 gave 1.38 at η = 1/3 against 1.23 and a strain rising with η (issue 32)."""
    text = write_card(load_card_data(damage_fit(fit_file)), "abaqus", "mm-s-t-N-MPa")
    key, _, rows = next(b for b in read_inp(text) if b[0] == "DAMAGE INITIATION")
    d1, d2, d3 = floats(rows)[0][:3]
    locus = fracture_strain(eta, 0.0, 0.0, **STEEL45)
    assert abaqus_failure_strain(d1, d2, d3, -eta) == pytest.approx(locus, rel=1e-9)
    assert abaqus_failure_strain(d1, d2, d3, -0.6) < abaqus_failure_strain(d1, d2, d3, -1 / 3)  # falls with η, as the fit


@pytest.mark.parametrize("version", ["2025", "2023"])
def test_openradioss_fail_johnson_fields(fit_file, version):
    text = write_card(load_card_data(damage_fit(fit_file)), "radioss", "mm-ms-kg-kN-GPa", radioss_version=version)
    blocks = dict(read_radioss(text))
    assert list(blocks) == ["/MAT/PLAS_JOHNS/1", "/FAIL/JOHNSON/1"]  # the failure model on the material's ID
    v = read_radioss_block(blocks["/FAIL/JOHNSON/1"], "JOHNSON", version)
    assert tuple(v[k] for k in STEEL45) == tuple(STEEL45.values())
    assert v["Epsilon_Dot_0"] == pytest.approx(LAW["rate0"] * 1e-3)  # per ms
    assert v["Ifail_so"] == 1  # a solid is deleted when one integration point fails
    if version == "2025":
        assert v["FAILIP"] == 1


def test_fracture_constants_in_the_header_with_their_range_and_sign(fit_file):
    text = write_card(load_card_data(damage_fit(fit_file)), "lsdyna", "mm-s-t-N-MPa")
    comments = " ".join(line[2:].strip() for line in text.splitlines() if line.startswith("$ "))
    assert "D4 = 0.063 +/- 0.0011" in comments and "positive in tension" in comments
    assert "triaxiality 0.333 to 1.72" in comments


def test_no_fracture_constants_no_fail_card(fit_file):
    text = write_card(load_card_data(fit_file()), "radioss", "mm-s-t-N-MPa")
    assert [h for h, _ in read_radioss(text)] == ["/MAT/PLAS_JOHNS/1"]
    assert "DAMAGE INITIATION" not in write_card(load_card_data(fit_file()), "abaqus", "mm-s-t-N-MPa")
