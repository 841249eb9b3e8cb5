"""ISO 6892-1 rate / ISO 6892-2 temperature conformity, and result.json's `uncertainty` on a real record."""

import json
import math
from pathlib import Path

import numpy as np
import pytest

from flowcurve.identification.quality import conformity as cf

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize("rate, expected", [(0.00025, 2), (0.00030, 2), (0.000301, None), (0.0016, 3), (0.0067 * 1.2, 4),
                                            (0.00007 * 0.8, 1), (0.001, None)])
def test_method_a_ranges_are_plus_minus_20_percent(rate, expected):
    assert cf.method_a_range(rate) == expected


def constant(rate, stress_rate=None):
    """The three phases of a constant-rate test."""
    return {"elastic": {"strain_rate_per_s": rate, "stress_rate_MPa_per_s": stress_rate}, "yield": {"strain_rate_per_s": rate},
            "to_Rm": {"strain_rate_per_s": rate}}


def test_range_2_throughout_is_method_a_222():
    out = cf.testing_rate(constant(0.00025), E_MPa=None)
    assert out["conforms"] and out["method"] == "A" and out["designation"] == "ISO 6892-1:2019 A222"


def test_range_3_misses_rp_then_method_b_decides():
    ok = cf.testing_rate(constant(0.002, 30.0), E_MPa=210_000.0)
    assert ok["method"] == "B" and ok["designation"] == "ISO 6892-1:2019 B30"
    assert any("method A: not met in elastic, yield" in f for f in ok["findings"])
    fast = cf.testing_rate(constant(0.002, 144.0), E_MPa=210_000.0)
    assert fast["conforms"] is False and any("6–60 MPa/s" in f for f in fast["findings"])
    soft = cf.testing_rate(constant(0.002, 30.0), E_MPa=70_000.0)  # aluminium: 2–20 MPa/s
    assert soft["conforms"] is False and any("2–20 MPa/s" in f for f in soft["findings"])


@pytest.mark.parametrize("T, tol", [(300, 3), (600, 3), (600.5, 4), (800, 4), (900, 5), (1000, 5), (1100, None)])
def test_iso_6892_2_tolerance_table(T, tol):
    assert cf.heated_tolerance_C(T) == tol


def test_heated_temperature_conformity():
    assert cf.temperature(900.0, [897.0, 904.9, 900.0])["conforms"] is True
    out = cf.temperature(900.0, [894.8, 900.0])
    assert out["conforms"] is False and out["max_deviation_C"] == pytest.approx(5.2)
    assert cf.temperature(900.0, None)["conforms"] is None  # unmeasured: not stated either way
    assert cf.temperature(20.0, [19.0, 21.0])["conforms"] is True
    assert cf.temperature(20.0, [36.0])["conforms"] is False


def test_elastic_stress_rate_reads_the_slope_in_the_window():
    t = np.linspace(0, 100, 1001)
    s = np.minimum(30.0 * t, 400.0 + 0.5 * t)  # 30 MPa/s up to 400 MPa, then a plateau
    assert cf.elastic_stress_rate(t, s, (50.0, 300.0)) == pytest.approx(30.0)
    assert cf.elastic_stress_rate(t[:2], s[:2], (50.0, 300.0)) is None


def test_elastic_stress_rate_leaves_out_blank_cells():
    """A blank time cell in the elastic window (the CI campaign's case: LAPACK's SVD failed on a NaN)."""
    t = np.linspace(0, 100, 1001)
    s = np.minimum(30.0 * t, 400.0 + 0.5 * t)
    t[50], s[60] = np.nan, np.nan
    assert cf.elastic_stress_rate(t, s, (50.0, 300.0)) == pytest.approx(30.0)


def test_46NT71_result_json_has_the_rp02_budget(tmp_path):
    """identify the real INSTRON record: uncertainty.Rp02_MPa's components recomputed by hand."""
    from flowcurve.cli import main

    assert main(["identify", str(ROOT / "examples" / "data" / "46NT71.csv"), "--out", str(tmp_path), "--no-plots"]) == 0
    result = json.loads((tmp_path / "46NT71" / "result.json").read_text())
    unc = result["uncertainty"]
    assert "defaults" in unc["instruments"]["source"]
    b = unc["Rp02_MPa"]
    d0, Rp = 5.003, result["Rp02_MPa"]
    S0 = math.pi * d0 ** 2 / 4
    force = b["components"][0]
    assert force["value"] == pytest.approx(Rp * S0) and force["u"] == pytest.approx(Rp * S0 * 0.01 / math.sqrt(3))
    diam = b["components"][1]
    assert diam["contribution"] == pytest.approx(2 * Rp / d0 * math.hypot(0.01 / math.sqrt(12), 0.004 / math.sqrt(3)))  # resolution, micrometer MPE
    assert b["U"] == pytest.approx(2 * math.sqrt(sum(c["contribution"] ** 2 for c in b["components"])))
    assert 10 < b["U"] < 25  # force class 1 (~1.2 % of Rp) and the testing rate within method B's decade (~1.1 %)
    for key in ("E_MPa", "Rm_MPa", "Ag_pct", "A_pct", "Z_pct"):
        assert unc[key]["U"] > 0
    assert set(unc["hardening"]) == {"A_MPa", "B_MPa", "n"}
    rate = result["methods"]["conformity"]["testing_rate"]
    for phase in ("elastic", "yield", "to_Rm"):  # measured from the crosshead per phase: the header's constant speed over Lc = 30 mm
        assert rate["phases"][phase]["strain_rate_per_s"] == pytest.approx(0.0298304 / 30.0, rel=0.01), phase
    assert rate["strain_rate_definition"].startswith("ė_Lc = v_c/L_c")
    assert rate["designation"].startswith("ISO 6892-1:2019 B")


def test_instrument_classes_from_the_record_are_used(tmp_path):
    from flowcurve.cli import main

    assert main(["identify", str(ROOT / "examples" / "data" / "46NT71.csv"), "--out", str(tmp_path), "--no-plots",
                 "--set", "instruments.force_class=0.5"]) == 0
    unc = json.loads((tmp_path / "46NT71" / "result.json").read_text())["uncertainty"]
    assert unc["instruments"]["force_class"] == 0.5 and "defaults for" in unc["instruments"]["source"]
    assert unc["Rm_MPa"]["components"][0]["name"] == "force F (ISO 7500-1 class 0.5)"


class _Record:
    def __init__(self, meta, data=None):
        self.meta, self.data = meta, data


@pytest.mark.parametrize("result", [
    {"test": "tension"},
    {"test": "tension", "E_MPa": None, "record": {"specimen": {"d0_mm": 6.0}}, "methods": {}},
    {"test": "tension", "E_MPa": 2e5, "Rm_MPa": 400.0, "Rp02_MPa": 300.0, "A_pct": 20.0, "A_method": "extensometer",
     "record": {"specimen": {"d0_mm": 6.0}, "post": {}}, "methods": {"strain_source": "crosshead"}, "hardening": {"law": "voce"}},
    {"test": "compression", "friction_mu": 0.1, "friction_mu_range": [None, 0.2], "friction": "fe_table", "methods": {}},
    {"test": "compression", "friction_mu": 0.1, "friction_mu_range": [0.08, 0.12], "friction": {"siebel": None},
     "record": {"specimen": {"d0_mm": 6.0, "h0_mm": 7.0}, "post": {"hk_mm": 8.0}}, "methods": {}},
])
def test_attach_leaves_out_what_it_cannot_compute_and_never_raises(result):
    """Results with missing or odd inputs: the budgets that can be computed, no guessed ones, no error."""
    from flowcurve.identification.quality.assurance import attach

    attach(result, {}, _Record({"instruments.force_class": "not a number"}))
    unc = result["uncertainty"]
    assert unc["instruments"]["force_class"] == 1.0
    assert "not a positive number, default used: force_class 'not a number'" in unc["instruments"]["source"]
    for key, budget in unc.items():
        if isinstance(budget, dict) and "U" in budget:
            assert math.isfinite(budget["U"]) and budget["U"] >= 0, key
    if result["test"] == "tension" and "Rp02_MPa" in result and "engineering" not in result:
        assert "Rp02_MPa" not in unc  # no curve and no Johnson–Cook law: no plastic slope, so no Rp0.2 budget
    if "methods" in result:
        assert "conformity" in result["methods"]
