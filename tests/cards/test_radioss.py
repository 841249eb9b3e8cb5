"""OpenRadioss cards read at the field positions of OpenRadioss' own input definitions
(readers.RADIOSS_LAYOUTS, transcribed from hm_cfg_files/config/CFG/radioss2025/...)."""

import pytest

from flowcurve.reports.cards import load_card_data, write_card

from .conftest import LAW
from .readers import read_radioss, read_radioss_block

# Lab units (MPa, kg/m3, J/kgK, 1/s, Hz) into each deck system, worked by hand.
SYSTEMS = [("mm-s-t-N-MPa", dict(stress=1.0, density=1e-12, cp=1e6, rate=1.0)),
           ("m-s-kg-N-Pa", dict(stress=1e6, density=1.0, cp=1.0, rate=1.0)),
           ("mm-ms-kg-kN-GPa", dict(stress=1e-3, density=1e-9, cp=1.0, rate=1e-3))]


def blocks_of(text):
    return {header: lines for header, lines in read_radioss(text)}


@pytest.mark.parametrize("version", ["2025", "2023"])
@pytest.mark.parametrize("units, f", SYSTEMS)
def test_plas_johns_fields_where_openradioss_reads_them(fit_file, units, f, version):
    text = write_card(load_card_data(fit_file()), "radioss", units, radioss_version=version)
    blocks = blocks_of(text)
    assert list(blocks) == ["/MAT/PLAS_JOHNS/1"]
    title, *data = blocks["/MAT/PLAS_JOHNS/1"]
    assert title == "12Kh18N12M3TL"
    v = read_radioss_block(data, "PLAS_JOHNS", version)
    assert v["RHO_I"] == pytest.approx(7820.0 * f["density"], rel=1e-12)
    assert v["E"] == pytest.approx(194000.0 * f["stress"], rel=1e-12) and v["Nu"] == 0.25
    assert v["Iflag"] == 0  # classic a, b, n input
    assert (v["a"], v["b"], v["n"]) == pytest.approx((LAW["A"] * f["stress"], LAW["B"] * f["stress"], LAW["n"]), rel=1e-12)
    assert v["EPS_p_max"] is None and v["SIG_max0"] is None  # defaults: no failure strain, no cap
    assert v["c"] == LAW["C"] and v["EPS_DOT_0"] == pytest.approx(LAW["rate0"] * f["rate"], rel=1e-12)
    assert v["Fsmooth"] == 1 and v["F_cut"] == pytest.approx(1e4 * f["rate"], rel=1e-12)  # filter on, 10 kHz
    assert v["m"] == LAW["m"]
    assert (v["T_melt"], v["T_r"]) == pytest.approx((LAW["T_melt"] + 273.15, LAW["T_ref"] + 273.15), rel=1e-12)
    assert v["rhoC_p"] == pytest.approx(7820.0 * 462.0 * f["density"] * f["cp"], rel=1e-12)
    if version == "2025":
        assert v["T_max"] is None and v["Pmin"] is None


def test_id_offset_and_filter_frequency(fit_file):
    text = write_card(load_card_data(fit_file()), "radioss", "mm-ms-kg-kN-GPa", id_offset=500, fcut_hz=2000.0)
    blocks = blocks_of(text)
    assert list(blocks) == ["/MAT/PLAS_JOHNS/501"]
    v = read_radioss_block(blocks["/MAT/PLAS_JOHNS/501"][1:], "PLAS_JOHNS", "2025")
    assert v["F_cut"] == pytest.approx(2.0)  # 2000 Hz in 1/ms
