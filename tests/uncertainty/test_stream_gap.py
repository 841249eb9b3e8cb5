"""A load-cell stream gap the acquisition could not tell latency or loss of, in the budgets it can move
(identification/quality/stream_gap.py): the realignment in closed form, the events' own texts, and a synthetic
tension whose later forces a latency stamped a period late — its Rp0.2 and Ag within their new U of the fault-free
record's, the term the fault's own error, Rm without a term."""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pytest

from flowcurve.identification.identify import identify
from flowcurve.identification.quality import stream_gap
from flowcurve.record.format import Event
from tests.tension.conftest import make_record

# the acquisition's texts (acquisition/stream_notes.py), as a record carries them
UNDECIDED = ("load cell: a gap in its stream after 21.104 s could be lost frames or the line's latency growing — stamped as lost, "
             "so every later force may be stamped up to 10.000 s late against the crosshead")
IN_DOUBT = ("load cell: a gap in its stream after 5.000 s, across which the force stayed within its noise, taken as lost frames; "
            "had it been the line's latency growing, every later force is stamped up to 0.500 s late against the crosshead")


def test_gaps_reads_both_events_in_time_order():
    rec, _ = make_record()
    named = dataclasses.replace(rec, events=[Event(60.0, "stream_gap_undecided", UNDECIDED), Event(9.0, "stream_gap_in_doubt", IN_DOUBT),
                                             Event(1.0, "stream_latency", "load cell: its frames arrive 0.500 s (host) after they were sent")])
    assert stream_gap.gaps(named) == [(5.0, 0.5), (21.104, 10.0)]
    assert stream_gap.gaps(rec) == []


def test_realigned_force_of_a_ramp_is_the_ramp_a_doubt_later():
    """F = a + b·t: after the gap F_rec(t + δ) = F + b·δ (closed form), before it unchanged; two gaps add their doubts."""
    t = np.arange(0.0, 20.0, 0.5)
    f = 100.0 + 30.0 * t
    out = stream_gap.realigned_force(t, f, [(5.0, 1.0)])
    inner = (t > 5.0) & (t + 1.0 <= t[-1])
    np.testing.assert_allclose(out[inner], f[inner] + 30.0, rtol=0, atol=1e-9)
    np.testing.assert_array_equal(out[t <= 5.0], f[t <= 5.0])
    two = stream_gap.realigned_force(t, f, [(5.0, 1.0), (10.0, 0.5)])
    late = (t > 10.0) & (t + 1.5 <= t[-1])
    np.testing.assert_allclose(two[late], f[late] + 45.0, rtol=0, atol=1e-9)


def _latency_taken_as_loss(rec, after_s: float, doubt_s: float):
    """The record a latency of ``doubt_s`` from ``after_s`` stamped as lost frames leaves: F_rec(t) = F(t − δ) after the gap."""
    data = rec.data.copy()
    t, f = data["time_s"].to_numpy(dtype=float), data["force_N"].to_numpy(dtype=float)
    data["force_N"] = np.where(t > after_s, np.interp(t - doubt_s, t, f), f)  # F(t − δ)
    text = IN_DOUBT.replace("5.000", f"{after_s:.3f}").replace("0.500", f"{doubt_s:.3f}")
    return dataclasses.replace(rec, data=data, events=[*rec.events, Event(after_s + doubt_s, "stream_gap_in_doubt", text)])


def test_a_latency_stamped_late_lies_within_the_new_U_of_the_fault_free_values():
    """The realigned record is the fault-free one (δ a whole number of rows), so the term is the fault's own error:
    u = |Rp0.2(fault) − Rp0.2(fault-free)|, and likewise Ag; Rm (a maximum of the force values) has no term."""
    rec, _ = make_record()
    fault = _latency_taken_as_loss(rec, after_s=5.0, doubt_s=0.5)  # rows every 0.1 s; 5 s lies on the elastic line
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        truth = identify(rec).result["uncertainty"]
        got = identify(fault).result
    unc = got["uncertainty"]
    for key in ("Rp02_MPa", "Ag_pct"):
        b = unc[key]
        term = next(c for c in b["components"] if c["name"] == stream_gap.COMPONENT)
        error = abs(b["value"] - truth[key]["value"])
        assert error > 0.0
        assert term["u"] == pytest.approx(error, rel=0.02, abs=1e-9)
        assert error <= b["U"]
    assert all(c["name"] != stream_gap.COMPONENT for c in unc["Rm_MPa"]["components"])
    assert any(c["name"] == stream_gap.COMPONENT for b in unc["hardening"].values() if isinstance(b, dict) for c in b.get("components", []))


def test_a_budget_the_realigned_record_lacks_is_refused():
    """u = |Δ| where the realigned record states the value (U = k·√(u_old² + Δ²)); refused where it does not."""
    row = {"name": "force", "value": 300.0, "unit": "MPa", "u": 1.0, "sensitivity": 1.0, "basis": "class 1"}
    unc = {"Rp02_MPa": {"value": 300.0, "unit": "MPa", "u": 1.0, "U": 2.0, "k": 2.0, "components": [row]},
           "flow_stress_MPa": {"0.3": {"value": 500.0, "unit": "MPa", "u": 1.0, "U": 2.0, "k": 2.0, "components": []}},
           "hardening": {"n": {"value": 0.3, "unit": "1", "u": 0.01, "U": 0.02, "k": 2.0, "components": []}}}
    missing = stream_gap.widen(unc, {"Rp02_MPa": {"value": 303.0}, "flow_stress_MPa": {}, "hardening": {}})
    assert sorted(missing) == ["flow_stress_MPa 0.3", "n"]
    assert unc["Rp02_MPa"]["U"] == pytest.approx(2.0 * np.hypot(1.0, 3.0))
    stream_gap.refuse(unc, missing, "why")
    assert unc["flow_stress_MPa"]["0.3"]["U"] is None and unc["hardening"]["n"]["certifiable"] is False
    assert unc["Rp02_MPa"]["U"] == pytest.approx(2.0 * np.hypot(1.0, 3.0))


def test_the_second_identification_pins_only_a_window_a_given_one_could_hold():
    """The re-identifications (stream gap, filter lag) pin the result's E window as a given one, which needs
    GIVEN_WINDOW_POINTS samples: an automatic window drawn over fewer (a sparse record's) is left to the
    automatic choice again — pinned, the 850 C steel 45 12 Hz delay record's second identification failed
    ('only 3 samples … need 5') and every budget it moves was stated not certifiable."""
    from flowcurve.identification.indicator import GIVEN_WINDOW_POINTS
    from flowcurve.identification.quality.filter_lag import pinned_options

    def result(n):
        return {"hardening": {"law": "johnson_cook"}, "modulus": {"window_MPa": [20.0, 300.0], "n_points": n}}

    assert pinned_options(result(GIVEN_WINDOW_POINTS), "tension", {})["modulus_window_MPa"] == (20.0, 300.0)
    few = pinned_options(result(GIVEN_WINDOW_POINTS - 2), "tension", {})
    assert "modulus_window_MPa" not in few and few["law"] == "johnson_cook"
