"""The CalculiX card: structure, and a one-element run in ccx that must reproduce the card's
flow stress (and the Johnson–Cook law the synthetic curves came from)."""

import os
import shutil
import subprocess

import numpy as np
import pytest

from flowcurve.reports.cards import CardError, load_card_data, write_card

from .conftest import jc_MPa
from .readers import floats, read_dat, read_inp


def plastic_table(text):
    blocks = read_inp(text)
    (plastic,) = [rows for key, _, rows in blocks if key == "PLASTIC"]
    return floats(plastic)


def test_structure_and_table_rules(fit_file):
    text = write_card(load_card_data(fit_file()), "calculix", "mm-s-t-N-MPa")
    blocks = read_inp(text)
    keys = [k for k, _, _ in blocks]
    assert keys == ["MATERIAL", "ELASTIC", "DENSITY", "SPECIFIC HEAT", "PLASTIC"]
    assert blocks[4][1] == {}  # plain *PLASTIC: ccx 2.20 misreads HARDENING=JOHNSON COOK
    elastic = floats(blocks[1][2])
    assert elastic.tolist() == [[194000.0, 0.25]]
    assert floats(blocks[2][2])[0, 0] == pytest.approx(7.82e-9, rel=1e-9)
    table = plastic_table(text)
    for temp in (20.0, 400.0):
        rows = table[table[:, 2] == temp]
        assert 2 <= len(rows) <= 100
        assert rows[0, 1] == 0.0  # each temperature starts at zero plastic strain
        assert np.all(np.diff(rows[:, 1]) > 0)
        # the curve follows the law the data came from, within resampling error
        np.testing.assert_allclose(rows[1:, 0], jc_MPa(rows[1:, 1], 1e-3, temp), rtol=2e-3)
    assert sorted(set(table[:, 2])) == [20.0, 400.0]


def test_gpa_units_scale_stress_not_strain(fit_file):
    mpa = plastic_table(write_card(load_card_data(fit_file()), "calculix", "mm-s-t-N-MPa"))
    gpa = plastic_table(write_card(load_card_data(fit_file()), "calculix", "mm-ms-kg-kN-GPa"))
    np.testing.assert_allclose(gpa[:, 0], mpa[:, 0] * 1e-3, rtol=1e-9)
    np.testing.assert_array_equal(gpa[:, 1:], mpa[:, 1:])


def test_law_table_at_another_rate(fit_file):
    data = load_card_data(fit_file())
    text = write_card(data, "calculix", "mm-s-t-N-MPa", curves="law", strain_rate_per_s=1e-2)
    table = plastic_table(text)
    for temp in (20.0, 400.0):
        rows = table[table[:, 2] == temp]
        np.testing.assert_allclose(rows[:, 0], jc_MPa(rows[:, 1], 1e-2, temp), rtol=1e-9)


def test_missing_density_names_the_option(fit_file):
    with pytest.raises(CardError, match="--density"):
        write_card(load_card_data(fit_file(density_kg_per_m3=None)), "calculix", "mm-s-t-N-MPa")


ONE_ELEMENT = """*NODE, NSET=NALL
1, 0, 0, 0
2, 1, 0, 0
3, 1, 1, 0
4, 0, 1, 0
5, 0, 0, 1
6, 1, 0, 1
7, 1, 1, 1
8, 0, 1, 1
*ELEMENT, TYPE=C3D8, ELSET=EALL
1, 1, 2, 3, 4, 5, 6, 7, 8
*NSET, NSET=BOTTOM
1, 2, 3, 4
*NSET, NSET=TOP
5, 6, 7, 8
*NSET, NSET=XSYM
1, 4, 5, 8
*NSET, NSET=YSYM
1, 2, 5, 6
{material}*SOLID SECTION, ELSET=EALL, MATERIAL={name}
*INITIAL CONDITIONS, TYPE=TEMPERATURE
NALL, {temperature}
*STEP, NLGEOM, INC=1000
*STATIC
0.02, 1.0, 1e-6, 0.02
*BOUNDARY
BOTTOM, 3, 3, 0.0
XSYM, 1, 1, 0.0
YSYM, 2, 2, 0.0
TOP, 3, 3, -0.1
*EL PRINT, ELSET=EALL
S, PEEQ
*NODE PRINT, NSET=TOP
RF
*END STEP
"""


@pytest.mark.solver
@pytest.mark.skipif(shutil.which("ccx") is None, reason="CalculiX 'ccx' is not installed (apt-get install calculix-ccx)")
@pytest.mark.parametrize("temperature", [20.0, 400.0])
def test_one_element_compression_in_ccx_reproduces_the_card(fit_file, tmp_path, temperature):
    text = write_card(load_card_data(fit_file()), "calculix", "mm-s-t-N-MPa")
    table = plastic_table(text)
    rows = table[table[:, 2] == temperature]
    job = tmp_path / "job.inp"
    job.write_text(ONE_ELEMENT.format(material=text, name="12KH18N12M3TL", temperature=temperature))
    run = subprocess.run(["ccx", "-i", "job"], cwd=tmp_path, capture_output=True, text=True, timeout=120,
                         env={**os.environ, "OMP_NUM_THREADS": "1"})
    assert "*ERROR" not in run.stdout + run.stderr, run.stdout[-2000:]
    dat = read_dat((tmp_path / "job.dat").read_text())
    stresses, peeq, forces = dat["stresses"], dat["equivalent plastic strain"], dat["forces"]
    assert stresses[-1][0] == pytest.approx(1.0)  # the step ran to its end
    checked = 0
    for (t, s), (_, p), (_, f) in zip(stresses, peeq, forces):
        eps_p = p[:, 2].mean()
        if eps_p < 1e-3:
            continue
        szz = -s[:, 4].mean()  # Cauchy stress, compression positive
        card_stress = np.interp(eps_p, rows[:, 1], rows[:, 0])
        assert szz == pytest.approx(card_stress, rel=5e-3), (t, eps_p)
        if eps_p >= 0.002:  # below the first measured point the card is a straight line from zero
            assert szz == pytest.approx(float(jc_MPa(eps_p, 1e-3, temperature)), rel=5e-3), (t, eps_p)
        # reaction force over the current area (volume kept: A = A0·h0/h, elastic change < 0.1 %)
        h = 1.0 - 0.1 * t
        assert -f[:, 3].sum() / (1.0 / h) == pytest.approx(szz, rel=5e-3)
        checked += 1
    assert checked >= 30
    assert peeq[-1][1][:, 2].mean() > 0.09  # reached ~10 % plastic strain
