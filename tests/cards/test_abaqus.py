"""Abaqus card: structure and values read back at the positions of the Abaqus keyword reference."""

import numpy as np
import pytest

from flowcurve.reports.cards import load_card_data, write_card

from .conftest import LAW, jc_MPa
from .readers import floats, read_inp


@pytest.mark.parametrize("units, stress, rate", [("mm-s-t-N-MPa", 1.0, 1.0), ("mm-ms-kg-kN-GPa", 1e-3, 1e-3)])
def test_abaqus_johnson_cook_and_table(fit_file, units, stress, rate):
    text = write_card(load_card_data(fit_file()), "abaqus", units)
    blocks = read_inp(text)
    materials = [(i, opts["NAME"]) for i, (k, opts, _) in enumerate(blocks) if k == "MATERIAL"]
    assert [name for _, name in materials] == ["12KH18N12M3TL_JC", "12KH18N12M3TL_TABLE"]
    jc_start, table_start = materials[0][0], materials[1][0]
    jc = {k: (opts, rows) for k, opts, rows in blocks[jc_start:table_start]}
    assert jc["PLASTIC"][0] == {"HARDENING": "JOHNSON COOK"}
    A, B, n, m, t_melt, t_trans = floats(jc["PLASTIC"][1])[0]
    assert (A, B) == pytest.approx((LAW["A"] * stress, LAW["B"] * stress), rel=1e-9)
    assert (n, m) == pytest.approx((LAW["n"], LAW["m"]), rel=1e-9)
    assert (t_melt, t_trans) == pytest.approx((LAW["T_melt"], LAW["T_ref"]))  # °C, as the model
    assert jc["RATE DEPENDENT"][0] == {"TYPE": "JOHNSON COOK"}
    C, eps0 = floats(jc["RATE DEPENDENT"][1])[0]
    assert C == pytest.approx(LAW["C"]) and eps0 == pytest.approx(LAW["rate0"] * rate, rel=1e-9)
    assert floats(jc["ELASTIC"][1]).tolist() == [[pytest.approx(194000.0 * stress), 0.25]]
    table = {k: (opts, rows) for k, opts, rows in blocks[table_start:]}
    rows = floats(table["PLASTIC"][1])
    assert table["PLASTIC"][0] == {} and rows.shape[1] == 3
    for temp in (20.0, 400.0):
        r = rows[rows[:, 2] == temp]
        assert r[0, 1] == 0.0 and len(r) <= 100
        np.testing.assert_allclose(r[1:, 0] / stress, jc_MPa(r[1:, 1], 1e-3, temp), rtol=2e-3)
    assert floats(table["FRICTION"][1])[0, 0] == pytest.approx(0.11)
    assert blocks[-2][1] == {"NAME": "FRICTION_MU"}
