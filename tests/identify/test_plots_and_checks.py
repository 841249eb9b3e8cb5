"""Plots drawn from named curves, and the common record checks of identify()."""

from __future__ import annotations

import math

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
import pytest

from flowcurve.record.format import Record
from flowcurve.errors import RecordError
from flowcurve.identification.identify import check_record, force_noise_N
from flowcurve.record.summary import record_summary
from flowcurve.identification.outcome import Identification
from flowcurve.reports.plots import add_plots, axis_label

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def _ident(test: str) -> Identification:
    e = np.linspace(0.0, 0.4, 80)
    law = 105.0 + 1392.0 * e**0.642  # the seed's worked example (3.34)
    disp = np.linspace(0, 2.0, 300)
    force = 20.0 * (1 - np.exp(-3 * disp))
    curves = {
        "raw_diagram": pd.DataFrame({"displacement_mm": disp, "force_kN": force}),
        "corrected_diagram": pd.DataFrame({"displacement_mm": disp * 0.96, "force_N": force * 1e3}),
        "fit": pd.DataFrame({"true_plastic_strain": e, "true_stress_MPa": law}),
    }
    if test == "compression":
        for name, k in (("true_k_sigma", 0.95), ("true_siebel", 0.97), ("true_slab", 0.96)):
            curves[name] = pd.DataFrame({"true_plastic_strain": e, "true_stress_MPa": k * law})
    else:
        curves["engineering"] = pd.DataFrame({"strain": e, "stress_MPa": law / np.exp(e)})
        curves["true"] = pd.DataFrame({"true_plastic_strain": e, "true_stress_MPa": law})
    result = {"test": test, "hardening": {"law": "johnson_cook", "A_MPa": 105.0, "B_MPa": 1392.0, "n": 0.642},
              "record": {"name": "S1", "material": "12Kh18N12M3TL", "nominal_temperature_C": 20.0}}
    return Identification(result=result, true_curve=curves["fit"], curves=curves)


@pytest.mark.parametrize("test,expected", [("tension", {"diagram", "stress_strain"}),
                                           ("compression", {"diagram", "stress_strain", "corrections"})])
def test_add_plots_writes_pngs_and_closes_figures(tmp_path, test, expected):
    ident = add_plots(_ident(test))
    assert set(ident.plots) == expected
    before = set(plt.get_fignums())
    ident.write(tmp_path)
    for name in expected:
        data = (tmp_path / f"{name}.png").read_bytes()
        assert data.startswith(PNG_MAGIC) and len(data) > 5000
    assert set(plt.get_fignums()) == before  # every figure closed after saving


def test_axis_labels_carry_units():
    assert axis_label("true_stress_MPa") == "true stress, MPa"  # one style in every figure and report
    assert axis_label("displacement_mm") == "displacement, mm"
    assert axis_label("force_kN") == "force, kN"
    assert axis_label("true_plastic_strain") == "true plastic strain"
    assert axis_label("strain_rate_per_s") == "strain rate, 1/s"


def test_noise_estimate_recovers_known_sigma():
    rng = np.random.default_rng(7)
    sigma = 3.0
    # a ramp (the test itself) plus white noise of known σ: the trend must not inflate it
    force = np.linspace(0.0, 500.0, 20000) + rng.normal(0.0, sigma, 20000)
    assert force_noise_N(force) == pytest.approx(sigma, rel=0.05)


@pytest.mark.parametrize("n", [10, 1000, 100_001, 540_000])
def test_force_noise_thins_the_differences_as_np_diff_then_a_stride_would(n):
    """Only the thinned successive differences are taken: the very number of np.diff(F)[::step]."""
    from flowcurve.identification.identify import NOISE_SAMPLES
    from flowcurve.identification.iso6892 import mad_sigma

    force = np.cumsum(np.random.default_rng(n).normal(2.0, 3.0, n))
    force[n // 3] = np.nan  # a blank sample: its two differences left out
    d = np.diff(force)[:: max(1, n // NOISE_SAMPLES)]
    d = d[np.isfinite(d)]
    assert force_noise_N(force) == mad_sigma(d) / np.sqrt(2.0)
    assert force_noise_N(list(force)) == force_noise_N(force)


def _record(force, **meta):
    n = len(force)
    data = pd.DataFrame({"time_s": np.arange(n) * 0.1, "force_N": force, "crosshead_mm": np.arange(n) * 1e-3})
    base = {"test": "tension", "specimen.d0_mm": "6", "specimen.l0_mm": "30", "crosshead_speed_mm_per_s": "0.01"}
    base.update(meta)
    return Record(meta=base, data=data, source="r.csv")


def test_checks_pass_real_rise_and_reject_noise_and_units():
    rng = np.random.default_rng(3)
    ramp = np.linspace(0.0, 30e3, 500) + rng.normal(0, 5, 500)  # 30 kN on d0 = 6 mm ≈ 1061 MPa
    assert check_record(_record(ramp)) == []
    with pytest.raises(RecordError, match="force never rises above noise"):
        check_record(_record(rng.normal(0, 5, 500)))
    with pytest.raises(RecordError, match="check units"):
        check_record(_record(ramp / 1e3))  # kN numbers in a force_N column
    with pytest.raises(RecordError, match="only 5 samples"):
        check_record(_record(ramp[:5]))
    with pytest.raises(RecordError, match="'specimen.l0_mm' is missing"):
        check_record(_record(ramp, **{"specimen.l0_mm": ""}))


def test_cut_short_record_gives_warning_not_error():
    rec = _record(np.linspace(0.0, 30e3, 500))
    rec.truncated = True
    assert any("cut short" in w for w in check_record(rec))


def test_record_summary_nominal_strain_rate():
    s = record_summary(_record(np.linspace(0.0, 30e3, 500), **{"specimen.id": "T1", "nominal_temperature_C": "600"}))
    assert s["strain_rate_per_s"] == pytest.approx(0.01 / 30.0)
    assert s["nominal_temperature_C"] == 600.0 and s["specimen"] == {"d0_mm": 6.0, "l0_mm": 30.0, "id": "T1"}
    assert math.isclose(s["crosshead_speed_mm_per_s"], 0.01)
