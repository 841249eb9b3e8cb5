"""A set-point too close to the furnace's maximum is refused before anything heats (the stored heat after a working
switch-off carries the furnace above its set-point; past the maximum with the heater off it is named a stuck relay):
from ``flowcurve run`` (in-process virtual rig and a configured rig on ptys), the procedure itself and the console's
start request. Just outside the margin a heated test runs on the virtual rig on model time with no false alarm, and a
relay that welds shut at that set-point is still named."""

from __future__ import annotations

import argparse
import contextlib
import io
from types import SimpleNamespace

import pytest

from flowcurve.acquisition.procedure import Procedure, ProcedureError, TestSpec
from flowcurve.cli import main
from flowcurve.rig.config import SETPOINT_MARGIN_C, FrameConfig, FurnaceConfig, setpoint_refusal
from tests.acquisition.conftest import run_logged as run_cli_logged

MAX_C = 900.0  # the configuration's default maximum
INSIDE_C = MAX_C - SETPOINT_MARGIN_C + 1.0  # 1 C inside the margin
EDGE_C = MAX_C - SETPOINT_MARGIN_C  # the highest set-point allowed


def words_of_the_refusal(text: str, setpoint_C: float) -> None:
    """The one line names the set-point, the maximum, the margin and why."""
    assert text.count("\n") == 0, text
    assert f"got {setpoint_C:g}" in text and f"maximum {MAX_C:g} C" in text and f"leave {SETPOINT_MARGIN_C:g} C below" in text
    assert "after the heater switches off" in text and "stuck relay" in text and f"at most {EDGE_C:g} C" in text


def cli(*argv):
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main([str(a) for a in argv])
    return code, out.getvalue(), err.getvalue()


def test_the_rule_is_the_maximum_less_the_margin():
    assert setpoint_refusal(EDGE_C, MAX_C) is None and setpoint_refusal(EDGE_C - 100.0, MAX_C) is None
    words_of_the_refusal(setpoint_refusal(INSIDE_C, MAX_C), INSIDE_C)
    assert setpoint_refusal(899.0, MAX_C, margin_C=0.5) is None and setpoint_refusal(899.6, MAX_C, margin_C=0.5)


def test_run_on_the_virtual_rig_refuses_a_set_point_inside_the_margin_before_the_rig_is_made(tmp_path, monkeypatch):
    import flowcurve.acquisition.session as session

    made = []
    monkeypatch.setattr(session, "run_virtual_test", lambda *a, **k: made.append(a))
    code, out, err = cli("run", "compression", "--quiet", "--temperature", f"{INSIDE_C:g}", "--out", tmp_path / "r.csv")
    assert code == 2 and not made and not (tmp_path / "r.csv").exists(), err
    assert err.startswith(f"flowcurve: error: --temperature must leave {SETPOINT_MARGIN_C:g} C below"), err
    words_of_the_refusal(err.strip(), INSIDE_C)


def test_run_on_a_configured_rig_refuses_it_with_nothing_switched_on(tmp_path, monkeypatch):
    """The configured rig's own maximum and margin, read from its file; the rig is not even opened."""
    import flowcurve.acquisition.session as session
    from flowcurve.rig.config import to_toml, virtual_config
    from flowcurve.rig.virtual.rig import VirtualRig

    def opened(rig):
        raise AssertionError("the rig was opened for a set-point inside the margin")

    monkeypatch.setattr(session.DriverRig, "__enter__", opened)
    with VirtualRig("steel45", test="tension") as vr:
        cfg = tmp_path / "rig.toml"
        cfg.write_text(to_toml(virtual_config(**{**vr.config_kwargs(), "max_temperature_C": MAX_C})))
        code, _, err = cli("run", "tension", "--config", cfg, "--quiet", "--d0", "6", "--l0", "30", "--temperature",
                           f"{INSIDE_C:g}", "--out", tmp_path / "r.csv")
        module, furnace = vr.devices["furnace"], vr.sync().furnace
        assert code == 2 and "stuck relay" in err and not (tmp_path / "r.csv").exists(), err
        words_of_the_refusal(err.strip(), INSIDE_C)
        assert module.do == 0 and not furnace.relay_on and len(furnace._switches) == 1  # never switched on
        assert abs(furnace.temperature_C - furnace.p.ambient_C) < 1e-9  # nothing heated


def test_a_configured_margin_is_the_rigs_own(tmp_path):
    """[furnace] setpoint_margin_C: a furnace measured to carry less stored heat may run closer to its maximum."""
    from flowcurve.services.run import out_of_range

    args = argparse.Namespace(temperature=897.0)
    tight = SimpleNamespace(frame=FrameConfig(), furnace=FurnaceConfig(port="x", max_temperature_C=MAX_C, setpoint_margin_C=2.0))
    assert out_of_range(args, tight) == {}
    default = SimpleNamespace(frame=FrameConfig(), furnace=FurnaceConfig(port="x", max_temperature_C=MAX_C))
    assert f"must leave {SETPOINT_MARGIN_C:g} C below" in out_of_range(args, default)["temperature"]


def test_the_procedure_refuses_it_before_heating(tmp_path, fake_rig):
    rig = fake_rig(max_temperature_C=MAX_C)
    spec = TestSpec("tension", geometry_mm={"d0_mm": 6.0, "l0_mm": 30.0}, temperature_C=INSIDE_C)
    with pytest.raises(ProcedureError) as refused:
        Procedure(rig, spec, tmp_path / "r.csv")
    assert str(refused.value).startswith(f"set-point must leave {SETPOINT_MARGIN_C:g} C below")
    words_of_the_refusal(str(refused.value), INSIDE_C)
    assert not rig.heater and not (tmp_path / "r.csv").exists()


def test_the_consoles_start_request_refuses_it_beside_the_temperature_field(tmp_path, monkeypatch):
    pytest.importorskip("starlette", reason="starlette is not installed (pip install -e .[test])")
    pytest.importorskip("httpx", reason="httpx is not installed (pip install -e .[test])")
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        from starlette.testclient import TestClient
    import flowcurve.acquisition.session as session
    from flowcurve.console.server import Console, create_app

    made = []
    monkeypatch.setattr(session, "run_virtual_test", lambda *a, **k: made.append(a))  # nothing may start
    console = Console(tmp_path / "out", time_scale=60.0)
    client = TestClient(create_app(console), base_url="http://127.0.0.1:8080")
    r = client.post("/api/start", json={"test": "compression", "temperature": f"{INSIDE_C:g}"},
                    headers={"Content-Type": "application/json"})
    assert r.status_code == 400 and set(r.json()["fields"]) == {"temperature"}, r.text
    said = r.json()["fields"]["temperature"]
    assert said.startswith("Temperature, °C must leave") and console.runner.current is None and not made
    words_of_the_refusal(said, INSIDE_C)


# -- just outside the margin, on the virtual rig on model time ------------------------------------------------------


def run_logged(tmp_path, monkeypatch, *extra):
    """``flowcurve run compression --temperature EDGE_C`` from 20 C, at the real rig's pace (time scale 1: the
    controller's on-times as on the rig), on model time (conftest.run_logged)."""
    return run_cli_logged(tmp_path, monkeypatch, ["compression", "--quiet", "--speed", "0.5", "--target", "3", "--time-scale", "1",
                                                  "--temperature", f"{EDGE_C:g}", "--soak", "60", "--material", "steel45", *extra])


def test_a_set_point_at_the_margin_heats_tests_and_cools_with_no_false_alarm(tmp_path, monkeypatch):
    code, said, rec, vr, readings = run_logged(tmp_path, monkeypatch)
    assert code == 0 and rec.meta["status"] == "complete", said[-600:]
    assert "relay stuck" not in said and not [e for e in rec.events if e.name == "fault"]
    last_on = max(i for i, (_, _, on) in enumerate(readings) if on)
    after_off = [value for _, value, _ in readings[last_on + 1:]]
    assert len(after_off) > 40  # the watch after the test read on
    assert max(after_off) > EDGE_C  # the stored heat did carry it above the set-point ...
    assert max(value for _, value, _ in readings) < MAX_C  # ... and nothing came near the maximum
    assert vr.devices["furnace"].do == 0 and not vr.model.furnace.relay_on


def test_a_relay_stuck_at_that_set_point_is_still_named(tmp_path, monkeypatch):
    code, said, rec, vr, readings = run_logged(tmp_path, monkeypatch, "--fault", "furnace:relay_stuck@5")
    assert code == 4, said[-600:]
    assert "relay stuck" in said and "mains power" in said
    assert [e for e in rec.events if e.name == "fault" and "relay stuck" in e.text]
    assert vr.devices["furnace"].do == 0 and vr.model.furnace.relay_on  # the output off; only the mains can stop it
    assert max(value for _, value, _ in readings) < MAX_C + 2.0  # named at the crossing


def test_without_the_margin_a_healthy_test_at_1_C_under_the_maximum_ends_in_a_safety_stop(tmp_path):
    """Why the margin: ``setpoint_margin_C = 0`` lets a set-point 1 C under the maximum through, and the heat stored
    while the controller's heater was on (up to 2.6 C measured) carries a healthy furnace past the maximum in an
    off-time of the controller's cycle: named a stuck relay — exit 4, the mains to be cut, for nothing."""
    from flowcurve.acquisition.session import run_virtual_test
    from flowcurve.clock import ModelClock

    spec = TestSpec("compression", material="steel45", geometry_mm={"d0_mm": 5.989, "h0_mm": 6.982}, temperature_C=MAX_C - 1.0,
                    speed_mm_per_s=0.5, soak_s=60.0)
    spec.stop.target_displacement_mm = 3.0
    rigs = []
    run = run_virtual_test(spec, tmp_path / "r.csv", material="steel45", time_scale=1.0, clock=ModelClock(), link="inprocess",
                           rig_setup=rigs.append, config_overrides={"furnace_max_temperature_C": MAX_C, "furnace_setpoint_margin_C": 0.0})
    out = run.outcome
    assert out.error is not None and out.error.exit_code == 4, (out.status, out.reason)
    assert "relay stuck" in str(out.error) and f"above the maximum {MAX_C:g} C" in str(out.error)
    assert not rigs[0].model.furnace.relay_on  # the relay works: the stop was for nothing
