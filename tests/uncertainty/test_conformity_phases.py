"""The testing rate measured per phase from the record (elastic, yield, to Rm), judged by ISO 6892-1
methods A and B as the standard writes them, by ISO 6892-2 when heated; "not stated" where the record
does not state it. The records: a Johnson–Cook tension test through a 136 N/µm frame whose time axis is
built from chosen crosshead speeds, switched where the identification finds Rp0.2."""

import json
import math
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from flowcurve.identification.quality.assurance import attach
from flowcurve.identification.tension.identify import identify_tension

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tests" / "tension"))
from conftest import make_record  # noqa: E402

LC_MM = 36.0  # the parallel length: the rate is v/Lc, not v/L0 (30 mm)


def record_at(rate_to_rp, rate_after, *, temperature_C=None, measured_C=None):
    """The record with ė_Lc = rate_to_rp (1/s) up to the Rp0.2 crossing and rate_after from it on.
    Rp0.2 does not depend on time: one identification of the record finds the crossing."""
    rec, _ = make_record(extensometer=False, noise_N=2.0)
    rec.meta["rig.frame_stiffness_N_per_um"] = "136"
    rec.meta["specimen.parallel_length_mm"] = repr(LC_MM)
    rec.meta["crosshead_speed_mm_per_s"] = repr(rate_to_rp * LC_MM)  # the header states the first speed only
    first = identify_tension(rec)
    stress = first.curves["engineering"]["engineering_stress_MPa"].to_numpy()
    lo, hi = first.result["modulus_window_MPa"]
    past_line = int(np.flatnonzero((stress >= lo) & (stress <= hi))[-1])
    k = past_line + int(np.argmax(stress[past_line:] >= first.result["Rp02_MPa"]))
    x = rec.data["crosshead_mm"].to_numpy()
    speed = np.where(np.arange(x.size - 1) < k, rate_to_rp, rate_after) * LC_MM  # interval i → i+1 at the speed of sample i
    time = np.concatenate([[0.0], np.cumsum(np.diff(x) / speed)])
    data = rec.data.assign(time_s=time)
    if temperature_C is not None:
        rec.meta["nominal_temperature_C"] = repr(temperature_C)
        data = data.assign(temperature_C=np.full(x.size, temperature_C if measured_C is None else measured_C))
    rec.data = data
    return rec


def conformity(rec):
    ident = identify_tension(rec)
    result = ident.result
    attach(result, ident.curves, rec)
    return result["methods"]["conformity"]


def test_a_speed_change_after_yield_is_measured_per_phase():
    """Range 2 to Rp, range 4 after: ISO 6892-1 A224 (the header's first speed alone said A222)."""
    rate = conformity(record_at(0.00025, 0.0067))["testing_rate"]
    for phase, expected in (("elastic", 0.00025), ("yield", 0.00025), ("to_Rm", 0.0067)):
        assert rate["phases"][phase]["strain_rate_per_s"] == pytest.approx(expected, rel=0.02), phase
    assert rate["conforms"] is True and rate["designation"] == "ISO 6892-1:2019 A224"
    assert "L_c 36 mm" in rate["strain_rate_definition"]


def test_too_fast_after_yield_conforms_to_neither_method():
    """0.02 1/s after Rp: above range 4 (≤ 0.00804) and above method B's 0.008 for Rm."""
    rate = conformity(record_at(0.00025, 0.02))["testing_rate"]
    assert rate["phases"]["to_Rm"]["strain_rate_per_s"] == pytest.approx(0.02, rel=0.02)
    assert rate["conforms"] is False and rate["designation"].endswith("(testing rate not conforming)")
    assert any("strain rate to Rm" in f and "outside" in f for f in rate["findings"])


def test_method_b_rp_has_no_lower_strain_rate_limit():
    """Method B for Rp: the elastic stress rate in Table 4 and at most 0.0025 1/s up to Rp; 0.00025 is
    the lower limit for ReL only (the old check applied it to Rp). 0.0001 1/s is in no method A range."""
    rate = conformity(record_at(0.0001, 0.005))["testing_rate"]
    # the elastic stress rate: ė·Lc over the crosshead compliance l0/E + S0/C of specimen and frame
    expected = 0.0001 * LC_MM / (30.0 / 200_000.0 + math.pi * 9.0 / 136_000.0)
    assert rate["phases"]["elastic"]["stress_rate_MPa_per_s"] == pytest.approx(expected, rel=0.03)
    assert rate["conforms"] is True and rate["method"] == "B" and rate["designation"] == f"ISO 6892-1:2019 B{expected:.0f}"


def test_heated_tests_are_judged_by_iso_6892_2():
    """At 600 °C ISO 6892-2's ranges: range 3 is 0.0014 1/s (0.002 1/s, range 3 of ISO 6892-1, is in none), and its method B's
    limits (0.0000167–0.0000833 1/s to yield) are not ISO 6892-1's."""
    ok = conformity(record_at(0.00025, 0.0014, temperature_C=600.0, measured_C=601.0))
    assert ok["temperature"]["standard"] == "ISO 6892-2:2018" and ok["temperature"]["conforms"] is True
    assert ok["testing_rate"]["conforms"] is True and ok["testing_rate"]["designation"] == "ISO 6892-2:2018 A223"
    bad = conformity(record_at(0.00025, 0.002, temperature_C=600.0, measured_C=601.0))["testing_rate"]
    assert bad["standard"] == "ISO 6892-2:2018" and bad["conforms"] is False
    room = conformity(record_at(0.00025, 0.002, temperature_C=20.0))["testing_rate"]  # the same rates at room temperature
    assert room["conforms"] is True and room["designation"] == "ISO 6892-1:2019 A223"
    slow = conformity(record_at(0.00005, 0.001, temperature_C=600.0, measured_C=599.0))["testing_rate"]
    assert slow["conforms"] is True and slow["method"] == "B" and slow["designation"] == "ISO 6892-2:2018 B"


def test_rt_and_no_temperature_are_not_stated(tmp_path):
    """The INSTRON header says 'RT': the models take 23 °C, the conformity says "not stated" (it said "conforms")."""
    from flowcurve.cli import main

    assert main(["identify", str(ROOT / "examples" / "data" / "46NT71.csv"), "--out", str(tmp_path), "--no-plots"]) == 0
    temp = json.loads((tmp_path / "46NT71" / "result.json").read_text())["methods"]["conformity"]["temperature"]
    assert temp["conforms"] is None and temp["stated_as"] == "RT" and "not stated" in temp["findings"][0]
    bare = conformity(record_at(0.00025, 0.00025))["temperature"]  # no temperature in the record at all
    assert bare["conforms"] is None and "not stated" in bare["findings"][0]


def test_no_time_column_is_not_stated():
    rec = record_at(0.00025, 0.00025)
    rec.data = rec.data.drop(columns="time_s")
    rate = conformity(rec)["testing_rate"]
    assert rate["conforms"] is None and "not stated" in rate["designation"]
