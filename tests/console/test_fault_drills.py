"""The set-up form's fault drill (issue 31): ``run --fault``'s syntax on the virtual rig, refused
beside its field when malformed or on a configured rig, declared in the record as ``run`` does."""

from __future__ import annotations

import time
import warnings

import pytest

pytest.importorskip("starlette", reason="starlette is not installed (pip install -e .[test])")
pytest.importorskip("httpx", reason="httpx is not installed (pip install -e .[test])")

with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    from starlette.testclient import TestClient  # noqa: E402

from flowcurve.console.server import Console, create_app  # noqa: E402
from flowcurve.record.format import read_record  # noqa: E402
from flowcurve.rig.virtual.fault_spec import parse_faults  # noqa: E402

JSON = {"Content-Type": "application/json"}
BASE_URL = "http://127.0.0.1:8080"


def _client(tmp_path, **kw) -> tuple[Console, TestClient]:
    console = Console(tmp_path / "out", time_scale=kw.pop("time_scale", 60.0), **kw)
    return console, TestClient(create_app(console), base_url=BASE_URL)


def _configured(tmp_path):
    from flowcurve.rig.config import virtual_config

    config = virtual_config({"loadcell": "/dev/null-a", "encoder": "/dev/null-b", "furnace": "/dev/null-c"})
    return _client(tmp_path, config=config)


@pytest.mark.parametrize("text, words", [
    ("loadcell", "DEVICE:KIND[:VALUE][@SECONDS]"),
    ("scale:drop", "one of loadcell, encoder, furnace"),
    ("loadcell:melt", "one of silence, drop, garble"),
    ("loadcell:relay_stuck", "applies to furnace, not the loadcell"),
    ("loadcell:garble:1.5", "fraction of replies, 0..1"),
    ("loadcell:corrupt@-3", "SECONDS must be >= 0"),
    ("encoder:jump:50 furnace:silence:2", "'silence' takes no VALUE"),
])
def test_a_bad_drill_is_a_400_beside_the_field_saying_what_is_allowed_and_starts_nothing(tmp_path, text, words):
    console, client = _client(tmp_path)
    r = client.post("/api/start", json={"test": "tension", "fault": text}, headers=JSON)
    assert r.status_code == 400, r.text
    fields = r.json()["fields"]
    assert set(fields) == {"fault"}
    assert fields["fault"].startswith("Fault drill ") and words in fields["fault"], fields
    assert console.runner.current is None
    assert not (tmp_path / "out" / "records").exists() or not any((tmp_path / "out" / "records").iterdir())


def test_a_drill_on_a_configured_rig_is_refused_and_the_page_is_not_offered_it(tmp_path):
    console, client = _configured(tmp_path)
    assert client.get("/api/info").json()["fault_help"] is None
    r = client.post("/api/start", json={"test": "compression", "fault": "loadcell:drop"}, headers=JSON)
    assert r.status_code == 400, r.text
    assert "virtual rig only" in r.json()["fields"]["fault"]
    assert console.runner.current is None


def test_the_virtual_rig_offers_the_kinds_per_device(tmp_path):
    _console, client = _client(tmp_path)
    info = client.get("/api/info").json()
    assert info["virtual"] is True
    assert "relay_stuck [furnace]" in info["fault_help"] and "jump [encoder]" in info["fault_help"]


@pytest.mark.parametrize("value, status", [(5, 400), (["loadcell:drop"], 400), ("x" * 201, 400)])
def test_the_request_guard_types_the_new_field(tmp_path, value, status):
    console, client = _client(tmp_path)
    r = client.post("/api/start", json={"test": "tension", "fault": value}, headers=JSON)
    assert r.status_code == status and "fault" in r.json()["fields"], r.text
    assert console.runner.current is None


def test_a_drill_from_another_origin_is_refused(tmp_path):
    console, client = _client(tmp_path)
    r = client.post("/api/start", json={"test": "tension", "fault": "furnace:silence"}, headers={**JSON, "Origin": "http://elsewhere.example"})
    assert r.status_code == 403
    assert console.runner.current is None


def test_a_drill_runs_and_the_record_declares_it_as_run_does(tmp_path):
    """Two drills, comma and space separated: the record's ``virtual.faults`` is what ``run --fault
    A --fault B`` writes, and the drill happened (the garbled frames are named in the events)."""
    console, client = _client(tmp_path, time_scale=60.0)
    r = client.post("/api/start", json={"test": "tension", "fault": " loadcell:garble:0.05, encoder:corrupt@2 "}, headers=JSON)
    assert r.status_code == 200, r.text
    end = time.monotonic() + 120
    while console.runner.current.running and time.monotonic() < end:
        time.sleep(0.1)
    run = console.runner.current
    assert not run.running
    rec = read_record(run.record)
    declared = " ".join(f.describe() for f in parse_faults(["loadcell:garble:0.05", "encoder:corrupt@2"]))
    assert rec.meta["virtual.faults"] == declared == "loadcell:garble:0.05 encoder:corrupt:50@2"
    assert run.setup.faults == parse_faults(["loadcell:garble:0.05", "encoder:corrupt@2"])
