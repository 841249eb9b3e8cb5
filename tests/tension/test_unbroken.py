"""Issue 42: a tension test stopped at a target (no fracture) identifies. The twin writes no
fracture values for an unbroken bar, and a record that says its specimen did not break (its
stop reason, its force) has its fracture values left out: no A, no Z, said why; the rest reported."""

from dataclasses import replace

import pytest

from flowcurve.acquisition.stopping import StopCriteria
from flowcurve.acquisition.session import run_virtual_test
from flowcurve.demo import demo_specs
from flowcurve.identification.identify import identify
from flowcurve.record.format import read_record

MATERIAL = "12Kh18N12M3TL"


@pytest.fixture(scope="module")
def stopped_at_3mm(tmp_path_factory):
    from flowcurve.clock import ModelClock

    spec = replace(demo_specs(MATERIAL)[0], stop=StopCriteria(target_displacement_mm=3.0))
    path = tmp_path_factory.mktemp("unbroken") / "t.csv"
    run = run_virtual_test(spec, path, material=MATERIAL, time_scale=15.0, clock=ModelClock(), link="inprocess")
    assert run.outcome.status == "complete" and "target displacement" in run.outcome.reason
    return run


def test_the_twin_writes_no_fracture_values_for_an_unbroken_bar(stopped_at_3mm):
    """Failed on the old twin: post.dk_mm = post.du_mm and a post.lu_mm for a bar that never broke."""
    meta = read_record(stopped_at_3mm.outcome.path).meta
    assert "post.du_mm" in meta
    assert not {"post.lu_mm", "post.dk_mm", "post.neck_radius_mm"} & set(meta)


def test_an_unbroken_tension_record_identifies_without_A_and_Z(stopped_at_3mm):
    rec = read_record(stopped_at_3mm.outcome.path)
    res = identify(rec).result
    assert res["A_pct"] is None and res["Z_pct"] is None
    assert any("did not break" in w and "no A, no Z" in w for w in res["warnings"])
    assert res["Rm_MPa"] > res["Rp02_MPa"] > 0 and res["hardening"]["B_MPa"] > 0  # Rp0.2, Rm and the uniform range's law


def test_fracture_values_in_a_record_that_says_it_did_not_break_are_left_out(stopped_at_3mm, tmp_path):
    """A record of the old twin (dk = du, an lu) or an operator's entry on an unbroken bar: identify
    refused ('the fracture strain … is below the strain at maximum force: check post.dk_mm')."""
    rec = read_record(stopped_at_3mm.outcome.path)
    du = rec.meta["post.du_mm"]
    rec.meta.update({"post.dk_mm": du, "post.lu_mm": "75.0"})
    res = identify(rec).result
    assert res["A_pct"] is None and res["Z_pct"] is None
    said = [w for w in res["warnings"] if "did not break" in w]
    assert said and "post.lu_mm, post.dk_mm left out" in said[0] and "target displacement" in said[0]


def test_a_broken_bar_keeps_its_fracture_values_whatever_the_stop_reason(stopped_at_3mm):
    """The rule needs both: a stop reason other than fracture AND a force that shows no break."""
    from flowcurve.identification.tension.values import unbroken_statement

    rec = read_record(stopped_at_3mm.outcome.path)
    assert unbroken_statement(rec) is not None
    rec.meta["stop_reason"] = "fracture (force fell below 20 % of the maximum 10.50 kN)"
    assert unbroken_statement(rec) is None
    del rec.meta["stop_reason"]  # a foreign record that does not say: its values are taken as they are
    assert unbroken_statement(rec) is None
