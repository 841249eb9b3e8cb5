"""Post-test measurements taken after a fault changed the specimen: the matrix's compression at 20 C
with a stuck relay (seed 190028814735116) stopped at its 3 mm target, then the furnace's watch held
the specimen under the stop's load for 9 s while it heated 16 C; it flowed on, hk came out 0.8 %
shorter than the fault-free run's, K_l scaled the strain by it and the flow curve read 3.4 % below
the material's, marked good. The rows are the fault-free run's: only the event after them tells."""

import math

import numpy as np
import pytest

from flowcurve.identification.identify import after_loading_warnings, identify
from flowcurve.identification.quality import post_test_doubt as doubt
from flowcurve.record.format import Event, Record

from .conftest import flow_stress


STUCK = Event(60.0, "fault", "furnace: heater does not switch off (relay stuck?): 16.2 C rise with the heater off for 9 s, still rising")


def _with(record: Record, *, events=(), hk_factor=1.0) -> Record:
    meta = dict(record.meta)
    meta["post.hk_mm"] = f"{float(meta['post.hk_mm']) * hk_factor:.4f}"
    return Record(meta=meta, data=record.data, source=record.source, events=list(events))


def _max_gap_pct(one: dict, other: dict, eps=np.linspace(0.1, 0.6, 11)) -> float:
    def sigma(result):
        h = result["hardening"]
        return h["A_MPa"] + h["B_MPa"] * eps ** h["n"]

    return float(100 * np.max(np.abs(sigma(one) / sigma(other) - 1)))


def test_a_specimen_heated_under_load_after_the_record_is_not_read_as_certified(make_record):
    record, _ = make_record(hk_target=4.3)  # the matrix cell's shortening: its clean reading is marked good
    end = float(record.data["time_s"].iloc[-1])
    late = Event(end + 9.0, STUCK.name, STUCK.text)
    clean = identify(record).result
    flowed = identify(_with(record, events=[late], hk_factor=0.985)).result  # hk as the matrix's cell left it: flowed on
    # the same rows, scaled to another hk: K_l as (3.1) gives it, and a curve 0.5 % and more away from the clean one's
    h0, hk = float(record.meta["specimen.h0_mm"]), float(record.meta["post.hk_mm"])
    springback = clean["indicator"]["springback_mm"]
    expected = clean["indicator"]["K_l"] * (h0 - 0.985 * hk + springback) / (h0 - hk + springback)
    assert abs(flowed["indicator"]["K_l"] / expected - 1) < 2e-3
    assert _max_gap_pct(flowed, clean) > 0.5
    said = [w for w in flowed["warnings"] if "after the loading's last row" in w]
    assert len(said) == 1 and "post.hk_mm" in said[0] and "heater does not switch off" in said[0], flowed["warnings"]
    assert clean["hardening"]["quality"] == "good" and not [w for w in clean["warnings"] if "after the loading" in w]
    assert flowed["hardening"]["quality"] == "poor"
    assert any("post-test measurements may be of a specimen changed" in w for w in flowed["hardening"]["warnings"])


def test_the_doubt_enters_the_budgets_and_they_hold_the_material(make_record):
    """The flowed record's budgets carry the spread between the measured hk and the record's own
    (the crosshead's shortening, frame compliance removed); with it each flow stress holds the law
    the record was made with, and the spread holds what the flowed hk moved: the fault-free run's
    flow stress within 2 u of it. (Before the flow stress stated the correction's own σ, the spread
    was also what held the law: without it some points missed; that σ now holds them on this record.)"""
    record, truth = make_record(hk_target=4.3)
    end = float(record.data["time_s"].iloc[-1])
    clean = identify(record).result
    flowed = identify(_with(record, events=[Event(end + 9.0, STUCK.name, STUCK.text)], hk_factor=0.985)).result
    # the record's own final height: the generator's unloaded hk within the crosshead's 0.01 mm step
    assert abs(doubt.record_final_height_mm(clean) - truth["hk"]) < 0.01
    assert abs(doubt.record_final_height_mm(flowed) - truth["hk"]) < 0.01
    for at, b in flowed["uncertainty"]["flow_stress_MPa"].items():
        (spread,) = [c for c in b["components"] if c["name"] == doubt.COMPONENT]
        error = abs(b["value"] - flow_stress(float(at), **truth["law"]))
        assert error <= b["U"], (at, b["value"], b["U"])
        moved = abs(b["value"] - clean["uncertainty"]["flow_stress_MPa"][at]["value"])  # what the flowed hk did
        assert 0.0 < moved <= 2.0 * spread["contribution"], (at, moved, spread["contribution"])
        assert b["u_method"] >= spread["contribution"]
    for b in (*flowed["uncertainty"]["hardening"].values(), flowed["uncertainty"]["friction_mu"]):
        assert doubt.COMPONENT in [c["name"] for c in b["components"]]
    budgets = (*clean["uncertainty"]["flow_stress_MPa"].values(), *clean["uncertainty"]["hardening"].values())
    assert all(doubt.COMPONENT not in [c["name"] for c in b["components"]] for b in budgets)
    assert any("the record's own" in w for w in flowed["warnings"])


def test_the_specimen_as_the_record_left_it_keeps_its_volume(seed_like_record):
    record, _ = seed_like_record
    hk, dmax = float(record.meta["post.hk_mm"]), float(record.meta["post.dmax_mm"])
    left = doubt.as_left_by_record(_with(record, events=[]), hk * 1.02)
    assert float(left.meta["post.hk_mm"]) == float(f"{hk * 1.02:.6g}")
    assert float(left.meta["post.dmax_mm"]) ** 2 * float(left.meta["post.hk_mm"]) == \
        pytest.approx(dmax**2 * hk, rel=1e-5)  # π/4·d²·h: the barrel's volume
    assert record.meta["post.hk_mm"] == f"{hk:.4f}"  # the record itself untouched


def test_only_a_heating_fault_after_the_last_row_is_held_against_the_post_test_measurements(seed_like_record):
    record, _ = seed_like_record
    end = float(record.data["time_s"].iloc[-1])
    assert after_loading_warnings(_with(record, events=[Event(end + 9.0, STUCK.name, STUCK.text)]))
    assert after_loading_warnings(_with(record, events=[Event(end + 1.0, "fault", "furnace: over-temperature: 1210.0 C above the configured maximum 1200.0 C; heater switched off")]))
    # during the loading: the rows carry it (their temperature column), not the post-test measurements alone
    assert after_loading_warnings(_with(record, events=[Event(end / 2, STUCK.name, STUCK.text)])) == []
    # after the loading, a fault that does not heat the specimen
    assert after_loading_warnings(_with(record, events=[Event(end + 1.0, "fault", "load cell: stream ('MSV?0') silent for 1.3 s")])) == []
    # no post-test measurements: nothing rests on them
    meta = {k: v for k, v in record.meta.items() if not k.startswith("post.")}
    assert after_loading_warnings(Record(meta=meta, data=record.data, source="x.csv", events=[Event(end + 9.0, STUCK.name, STUCK.text)])) == []
    assert math.isfinite(end)


def test_without_the_records_own_height_the_budgets_are_not_certified(seed_like_record, monkeypatch):
    """No second final height to compare with: the budgets resting on hk state no U, and say why."""
    record, _ = seed_like_record
    end = float(record.data["time_s"].iloc[-1])
    monkeypatch.setattr(doubt, "record_final_height_mm", lambda result: None)
    result = identify(_with(record, events=[Event(end + 9.0, STUCK.name, STUCK.text)])).result
    unc = result["uncertainty"]
    budgets = [*unc["flow_stress_MPa"].values(), *unc["hardening"].values(), unc["friction_mu"]]
    assert budgets and all(b["U"] is None and b["certifiable"] is False and "heating fault" in b["note"] for b in budgets)
    assert any(w.startswith("not certifiable: the record's own shortening") for w in result["warnings"])
