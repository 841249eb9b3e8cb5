"""ISO 6892-1 yield point: ReH, ReL and Ae on a curve built with them, none on a smooth curve."""

import math

import numpy as np
import pandas as pd
import pytest

from flowcurve.identification import iso6892
from flowcurve.identification.tension.identify import identify_tension
from flowcurve.record.format import Record

E, REH, REL, AE = 200_000.0, 450.0, 398.0, 0.015  # MPa, MPa, MPa (plateau minimum), strain


def yield_point_curve(noise_MPa=0.0, seed=0, n_elastic=60):
    """Engineering curve: elastic to ReH, a transient drop to 392 MPa (to be disregarded), a
    Lüders plateau 400 ± 2 MPa ending AE after ReH, then hardening to Rm and a falling neck."""
    e_el = np.linspace(0, REH / E, n_elastic)
    e_h = REH / E
    e_drop = e_h + np.linspace(0.0002, 0.001, 5)
    s_drop = np.array([430.0, 410.0, 392.0, 395.0, 399.0])
    e_pl = np.linspace(e_drop[-1] + 0.0002, e_h + AE, 150)
    s_pl = 400 + 2 * np.sin(np.linspace(0, 30, 150))
    e_hard = np.linspace(e_pl[-1] + 1e-4, 0.18, 300)
    s_hard = 400 + 300 * (1 - np.exp(-(e_hard - e_pl[-1]) / 0.05))
    e_neck = e_hard[-1] + np.linspace(0.001, 0.04, 40)
    s_neck = s_hard[-1] - np.linspace(1, 120, 40)
    e = np.concatenate([e_el, e_drop, e_pl, e_hard, e_neck])
    s = np.concatenate([e_el * E, s_drop, s_pl, s_hard, s_neck])
    s = s + np.random.default_rng(seed).normal(0, noise_MPa, s.size) * (np.arange(s.size) > 0)
    return e, s


def test_yield_point_by_construction():
    e, s = yield_point_curve()
    yp = iso6892.yield_point(e, s)
    assert yp["ReH_MPa"] == pytest.approx(REH)
    assert yp["ReL_MPa"] == pytest.approx(REL, abs=0.05)  # the 392 MPa transient disregarded
    assert yp["Ae_pct"] == pytest.approx(100 * AE, abs=0.05)


def test_no_yield_point_on_a_smooth_noisy_curve():
    e = np.linspace(0, 0.2, 2000)
    s = np.minimum(E * e, 400 + 300 * (1 - np.exp(-np.clip(e - 0.002, 0, None) / 0.05)))
    s = s + np.random.default_rng(1).normal(0, 0.5, s.size)
    assert iso6892.yield_point(e, s, noise_MPa=0.5) is None


def test_tension_reports_reh_rel_ae_and_fits_past_the_plateau(synthetic):
    e, s = yield_point_curve(noise_MPa=0.3)
    d0, l0 = 6.0, 30.0
    s0 = math.pi * d0**2 / 4
    data = pd.DataFrame({"time_s": np.arange(e.size) * 0.1, "force_N": s * s0, "crosshead_mm": e * l0, "extensometer_mm": e * l0})
    meta = {"test": "tension", "specimen.d0_mm": repr(d0), "specimen.l0_mm": repr(l0), "specimen.extensometer_gauge_mm": repr(l0)}
    r = identify_tension(Record(meta=meta, data=data, source="yield-point.csv")).result
    assert r["yield_point"] is True
    assert r["ReH_MPa"] == pytest.approx(REH, rel=0.01)
    assert r["ReL_MPa"] == pytest.approx(REL, rel=0.01)
    assert r["Ae_pct"] == pytest.approx(100 * AE, abs=0.1)
    assert any("yield point" in w for w in r["warnings"])
    # the hardening fit starts after the plateau
    assert r["hardening"]["fit_range"][0] >= AE - 0.003
    smooth = identify_tension(synthetic(noise_N=5.0)[0]).result  # continuous yielding (Johnson–Cook)
    assert smooth["yield_point"] is False and smooth["ReH_MPa"] is None and smooth["Ae_pct"] is None


def test_reh_on_a_crosshead_record_whose_line_runs_up_to_it():
    """The search starts at the elastic line's start, not its top (docs/methods.md §3.3a): SDAR's line on a
    crosshead-only record of a sharp yield point reaches ReH itself, and a search above its top found none."""
    e, s = yield_point_curve(noise_MPa=0.3, n_elastic=100)
    d0, l0 = 6.0, 30.0
    s0 = math.pi * d0**2 / 4
    data = pd.DataFrame({"time_s": np.arange(e.size) * 0.1, "force_N": s * s0, "crosshead_mm": e * l0})
    meta = {"test": "tension", "specimen.d0_mm": repr(d0), "specimen.l0_mm": repr(l0)}
    r = identify_tension(Record(meta=meta, data=data, source="yield-point-crosshead.csv")).result
    assert r["modulus_window_MPa"][1] > 0.99 * REH  # the case: the line's top at ReH
    assert r["yield_point"] is True and r["ReH_MPa"] == pytest.approx(REH, rel=0.005)
    assert r["ReL_MPa"] == pytest.approx(REL, rel=0.01)


DATA_42 = __import__("pathlib").Path(__file__).resolve().parents[1] / "data" / "42CrMoS4" / "original_data"


@pytest.mark.parametrize("name", ["46NT71", "46NT73", "46NT75"])
def test_the_42CrMoS4_specimens_that_drop_alike_are_classified_alike(name):
    """46NT71/73/75 drop 0.57, 1.07 and 0.52 % after their first maximum and stay below it for about
    0.5 % extension: each is an upper yield point (ISO 6892-1 3.10.2.1: the first decrease in force
    observed). The old 1 % threshold classed 46NT73 alone. ReH is checked against the raw record: the
    largest stress before it first falls 3 MPa (tens of noise σ) under its running maximum."""
    from flowcurve.identification.identify import identify
    from flowcurve.record.importers import load_record

    rec = load_record(DATA_42 / f"{name}.csv")
    r = identify(rec).result
    assert r["yield_point"] is True
    s = rec.column("force_N") / rec.positive("specimen.s0_mm2", required=True)
    below = np.flatnonzero(np.maximum.accumulate(s) - s > 3.0)
    assert r["ReH_MPa"] == pytest.approx(float(np.max(s[: below[0]])), rel=1e-9)
    assert r["ReH_MPa"] - r["ReL_MPa"] > 3.0 and r["ReL_MPa"] > r["Rp02_MPa"] - 10.0
    assert 0.3 < r["Ae_pct"] < 0.8  # the extension below the first maximum: about 0.5 %


def test_at_is_the_total_extension_at_fracture(synthetic):
    """At (ISO 6892-1 3.6.6): elastic and plastic extension at fracture, in % of the gauge length; A
    from the same extension is At less the elastic part σ_k/E. The record is cut at the break."""
    rec, info = synthetic()
    rec.data.loc[rec.data.index[-1], "force_N"] = 0.1 * info["Fm_N"]  # the break
    r = identify_tension(rec).result
    e_k = rec.data["extensometer_mm"].iloc[-2] / 30.0  # the last sample before the break
    assert r["At_pct"] == pytest.approx(100.0 * e_k, abs=1e-3)  # the toe compensation moves the zero by ~1e-6
    sigma_k = rec.data["force_N"].iloc[-2] / info["s0_mm2"]
    assert r["At_pct"] - r["A_pct"] == pytest.approx(100.0 * sigma_k / r["E_MPa"], rel=1e-6)
    assert "At_pct" in r.to_json() and r["A_method"].startswith("extensometer at fracture")
    cut, _ = synthetic()
    cut.data = cut.data.iloc[: int(np.argmax(cut.data["force_N"].to_numpy())) + 20].reset_index(drop=True)  # stopped just past Fm
    assert identify_tension(cut).result["At_pct"] is None  # no fracture in the record: no At
