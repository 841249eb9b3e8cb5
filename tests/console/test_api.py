"""The console's HTTP endpoints (no browser): form checks, one test at a time, the token,
paths that try to leave --out, and the heater off when the console shuts down mid-test."""

from __future__ import annotations

import time
import warnings
from pathlib import Path

import pytest

pytest.importorskip("starlette", reason="starlette is not installed (pip install -e .[test])")
pytest.importorskip("httpx", reason="httpx is not installed (pip install -e .[test])")

with warnings.catch_warnings():  # starlette's note about its test client's HTTP library
    warnings.simplefilter("ignore")
    from starlette.testclient import TestClient  # noqa: E402

from flowcurve.cli import main as cli_main  # noqa: E402
from flowcurve.console.server import Console, create_app  # noqa: E402
from flowcurve.record.format import read_record  # noqa: E402
from tests.console.conftest import identified_records  # noqa: E402

JSON = {"Content-Type": "application/json"}
BASE_URL = "http://127.0.0.1:8080"  # a name the console answers to (TestClient's own "testserver" is refused)


def _client(tmp_path: Path, **kw) -> tuple[Console, TestClient]:
    console = Console(tmp_path / "out", time_scale=kw.pop("time_scale", 60.0), **kw)
    return console, TestClient(create_app(console), base_url=BASE_URL)


def _wait(console: Console, states=("complete", "aborted", "failed"), timeout_s: float = 60.0) -> None:
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        run = console.runner.current
        if run is not None and not run.running and run.view.state in states:
            return
        time.sleep(0.05)
    raise AssertionError(f"test did not reach {states} in {timeout_s} s (state {console.runner.current.view.state})")


def _cli_error(argv: list[str], capsys) -> str:
    code = cli_main(argv)
    assert code != 0
    err = capsys.readouterr().err.strip()
    assert err.startswith("flowcurve: error: ")
    return err[len("flowcurve: error: "):]


def test_bad_values_are_refused_with_the_run_commands_words_beside_each_field(tmp_path, capsys):
    _console, client = _client(tmp_path)
    r = client.post("/api/start", json={"test": "compression", "d0": "-2", "speed": "fast", "target": "0"}, headers=JSON)
    assert r.status_code == 400
    fields = r.json()["fields"]
    assert set(fields) == {"d0", "speed", "target"}
    # the same value given to `flowcurve run` is refused with the same message, the field named as the form labels it
    assert fields["d0"] == _cli_error(["run", "compression", "--quiet", "--d0", "-2", "--out", str(tmp_path / "x.csv")], capsys).replace("--d0", "d0, mm")
    assert fields["target"] == _cli_error(["run", "compression", "--quiet", "--target", "0", "--out", str(tmp_path / "y.csv")], capsys).replace("--target", "Target, mm")
    assert fields["d0"].startswith("d0, mm must be more than 0 and at most 30 mm")
    assert "not a number" in fields["speed"] and fields["speed"].startswith("Speed, mm/s")
    assert not (tmp_path / "out" / "records").exists() or not list((tmp_path / "out" / "records").iterdir())


def test_a_set_point_the_furnace_refuses_goes_back_to_the_temperature_field_and_starts_nothing(tmp_path):
    """It used to start a test that failed at once: a red FAULT and a record name for a test that never ran."""
    console, client = _client(tmp_path)
    r = client.post("/api/start", json={"test": "compression", "temperature": "5000"}, headers=JSON)
    assert r.status_code == 400
    assert set(r.json()["fields"]) == {"temperature"}
    assert r.json()["fields"]["temperature"].startswith("Temperature, °C must be above 20 C")
    assert "below 900 C (the furnace's [furnace] max_temperature_C), got 5000" in r.json()["fields"]["temperature"]
    assert console.runner.current is None
    assert client.get("/api/status").json() == {"status": {"state": "idle", "heater": "off"}, "test": None}
    assert not (tmp_path / "out" / "records").exists() or not list((tmp_path / "out" / "records").iterdir())


@pytest.mark.parametrize("field, value, words", [
    ("temperature", "-300", "Temperature, °C must be above 20 C (room; leave it out for a test at room temperature) and below 900 C"),
    ("temperature", "20", "Temperature, °C must be above 20 C"),
    ("temperature", "900", "and below 900 C"),
    ("speed", "1e9", "Speed, mm/s must be between 0.001 and 2 mm/s (the machine's speed range"),
    ("speed", "0.0001", "Speed, mm/s must be between 0.001 and 2 mm/s"),
    ("target", "1e12", "Target, mm must be more than 0 and at most 250 mm (the crosshead travel, [frame] travel_mm)"),
    ("force_limit", "2e5", "Force limit, N must be more than 0 and at most 100000 N (the machine's capacity"),
    ("d0", "31", "d0, mm must be more than 0 and at most 30 mm (the largest diameter the grips and platens take"),
    ("h0", "1e12", "h0, mm must be more than 0 and at most 200 mm"),
    ("lc", "1e12", "Parallel length Lc, mm must be more than 0 and at most 200 mm"),
    ("soak", "1e12", "Soak, s must be more than 0 and at most 86400 s"),
])
def test_values_outside_the_rigs_ranges_are_refused_beside_their_field(tmp_path, field, value, words):
    """-300 °C, 1e9 mm/s and a 1e12 mm target were accepted (every field's limit was 1e12)."""
    console, client = _client(tmp_path)
    r = client.post("/api/start", json={"test": "compression", field: value}, headers=JSON)
    assert r.status_code == 400, r.text
    assert set(r.json()["fields"]) == {field}
    from flowcurve.console.setup_form import LABELS

    message = r.json()["fields"][field]
    assert message.startswith(f"{LABELS[field]} must be") and words in message, message
    assert console.runner.current is None


def test_a_configured_rigs_ranges_are_its_own_on_the_page_and_for_run(tmp_path, capsys):
    """The ranges come from the rig configuration: the same values are refused by the form and by run."""
    from flowcurve.console.setup_form import FormError, validate
    from flowcurve.rig.config import to_toml, virtual_config

    config = virtual_config({"loadcell": "/dev/null-a", "encoder": "/dev/null-b", "furnace": "/dev/null-c"}, max_temperature_C=500.0,
                            frame_min_speed_mm_per_s=0.01, frame_max_speed_mm_per_s=0.5, frame_travel_mm=40.0,
                            frame_max_specimen_diameter_mm=12.0, frame_max_specimen_length_mm=50.0)
    form = {"test": "tension", "temperature": "600", "speed": "0.6", "target": "41", "d0": "12.5", "l0": "60"}
    with pytest.raises(FormError) as refused:
        validate(form, virtual=False, time_scale=None, config=config)
    fields = refused.value.errors
    assert set(fields) == {"temperature", "speed", "target", "d0", "l0"}
    assert "below 500 C" in fields["temperature"] and "between 0.01 and 0.5 mm/s" in fields["speed"]
    assert "at most 40 mm" in fields["target"] and "at most 12 mm" in fields["d0"] and "at most 50 mm" in fields["l0"]
    path = tmp_path / "rig.toml"
    path.write_text(to_toml(config))
    err = _cli_error(["run", "tension", "--quiet", "--config", str(path), "--temperature", "600", "--speed", "0.6", "--target", "41",
                      "--d0", "12.5", "--l0", "60", "--out", str(tmp_path / "r.csv")], capsys)
    for field, option in (("temperature", "--temperature"), ("speed", "--speed"), ("target", "--target"), ("d0", "--d0"), ("l0", "--l0")):
        from flowcurve.console.setup_form import LABELS

        assert fields[field].replace(LABELS[field], option) in err, (option, err)  # run's words, the option for the label
    ok = validate({**form, "temperature": "450", "speed": "0.4", "target": "39", "d0": "6", "l0": "30"}, virtual=False, time_scale=None, config=config)
    assert ok.spec.temperature_C == 450.0 and ok.spec.speed_mm_per_s == 0.4


def test_a_parallel_length_shorter_than_l0_is_refused_beside_its_field_and_a_longer_one_reaches_the_test(tmp_path, capsys):
    from flowcurve.console.setup_form import LABELS, validate

    console, client = _client(tmp_path)
    r = client.post("/api/start", json={"test": "tension", "d0": "6", "l0": "30", "lc": "25"}, headers=JSON)
    assert r.status_code == 400, r.text
    assert set(r.json()["fields"]) == {"lc"}
    message = r.json()["fields"]["lc"]
    assert message.startswith(f"{LABELS['lc']} 25 mm is shorter than the gauge length l0 30 mm"), message
    assert message.replace(LABELS["lc"], "--lc") in _cli_error(["run", "tension", "--quiet", "--d0", "6", "--l0", "30", "--lc", "25",
                                                                  "--out", str(tmp_path / "r.csv")], capsys)  # run's words
    assert console.runner.current is None
    ok = validate({"test": "tension", "d0": "6", "l0": "30", "lc": "42"}, virtual=True, time_scale=None)
    assert ok.spec.geometry_mm == {"d0_mm": 6.0, "l0_mm": 30.0, "parallel_length_mm": 42.0}
    ok = validate({"test": "compression", "lc": "42"}, virtual=True, time_scale=None)  # the field is hidden there: ignored
    assert "parallel_length_mm" not in ok.spec.geometry_mm


def test_one_test_at_a_time_and_stop_gives_a_complete_record(tmp_path):
    console, client = _client(tmp_path, time_scale=5.0)
    r = client.post("/api/start", json={"test": "compression", "specimen_id": "C-a"}, headers=JSON)
    assert r.status_code == 200, r.text
    second = client.post("/api/start", json={"test": "compression"}, headers=JSON)
    assert second.status_code == 409
    end = time.monotonic() + 30
    while console.runner.current.view.samples < 20 and time.monotonic() < end:
        time.sleep(0.05)
    assert client.post("/api/stop", json={}, headers=JSON).json() == {"stopping": True}
    _wait(console)
    run = console.runner.current
    rec = read_record(run.record)
    assert rec.meta["status"] == "complete"
    assert rec.meta["stop_reason"] == "operator stop (console)"
    assert rec.meta["specimen.id"] == "C-a"
    assert ("stop", "operator stop (console)") in [(e.name, e.text) for e in rec.events]
    assert client.post("/api/stop", json={}, headers=JSON).json() == {"stopping": False}
    # every recorded row is a point of the live plot (the rows taken in the tick of a stop were lost: 1832 of 1841)
    assert len(run.view.force_displacement.x) == run.outcome.samples == len(rec.data)
    assert run.view.status()["state"] == "complete"


def start_then_abort(console: Console, client: TestClient, while_running=lambda: None) -> None:
    """A tension test started, aborted after ten samples (``while_running()`` first), ended."""
    assert client.post("/api/start", json={"test": "tension"}, headers=JSON).status_code == 200
    end = time.monotonic() + 30
    while console.runner.current.view.samples < 10 and time.monotonic() < end:
        time.sleep(0.05)
    while_running()
    assert client.post("/api/abort", json={}, headers=JSON).json() == {"aborting": True}
    _wait(console)


def test_abort_marks_the_record_aborted(tmp_path):
    console, client = _client(tmp_path, time_scale=5.0)
    start_then_abort(console, client)
    rec = read_record(console.runner.current.record)
    assert rec.meta["status"] == "aborted"
    assert "abort button" in rec.meta["abort_reason"]
    assert console.runner.current.view.status()["state"] == "aborted"  # not "done": its own word


def test_shutting_the_console_down_mid_heating_switches_the_heater_off_and_closes_the_record(tmp_path):
    console = Console(tmp_path / "out", time_scale=20.0)
    with TestClient(create_app(console), base_url=BASE_URL) as client:  # the context runs the app's lifespan (shutdown)
        r = client.post("/api/start", json={"test": "compression", "temperature": "300", "soak": "600"}, headers=JSON)
        assert r.status_code == 200, r.text
        run = console.runner.current
        end = time.monotonic() + 30
        while run.view.status()["heater"] != "on" and time.monotonic() < end:
            time.sleep(0.05)
        assert run.view.status()["heater"] == "on"  # the virtual furnace's relay is on while heating
    assert not run.running
    assert run.heater_source.relay_on is False
    text = run.record.read_text()  # no samples yet (aborted while heating): read the header as text
    assert "# status: aborted\n" in text
    assert "# abort_reason: stopped by the console shutting down\n" in text
    assert [line.split()[3] for line in text.splitlines() if line.startswith("# event:")] == ["heater_on", "heater_off", "stop"]


@pytest.mark.parametrize("path", [
    "/files/../../etc/passwd", "/files/%2e%2e/%2e%2e/etc/passwd", "/files/records/..%2f..%2f..%2fsecret.txt",
    "/files/%2Fetc%2Fpasswd", "/files/records/%2e%2e/%2e%2e/secret.txt", "/files/link/secret.txt", "/files/records/%5c..%5c..%5csecret.txt",
])
def test_files_outside_out_cannot_be_read(tmp_path, path):
    (tmp_path / "secret.txt").write_text("no")
    _console, client = _client(tmp_path)
    (tmp_path / "out").mkdir(exist_ok=True)
    (tmp_path / "out" / "link").symlink_to(tmp_path)  # a link inside --out pointing out of it
    r = client.get(path)
    assert r.status_code == 404
    assert r.text != "no"


def test_files_inside_out_are_served(tmp_path):
    _console, client = _client(tmp_path)
    (tmp_path / "out" / "records").mkdir(parents=True)
    (tmp_path / "out" / "records" / "a.csv").write_text("# flowcurve-record: 1\n")
    r = client.get("/files/records/a.csv")
    assert r.status_code == 200 and r.text == "# flowcurve-record: 1\n"


@pytest.mark.parametrize("name", ["../secret.csv", "/tmp/x.csv", "..", "records/../../x.csv", "a\\..\\b.csv"])
def test_no_endpoint_takes_a_path_out_of_out(tmp_path, name):
    _console, client = _client(tmp_path)
    r = client.post("/api/fit", json={"records": [name], "melt_temp": "1450"}, headers=JSON)
    assert r.status_code == 400
    assert "not a plain name" in r.json()["error"]
    written = [p for p in tmp_path.rglob("*") if p.is_file()]  # nothing written anywhere
    assert written == []


def test_posts_from_another_origin_or_not_json_are_refused(tmp_path):
    _console, client = _client(tmp_path)
    r = client.post("/api/start", json={"test": "compression"}, headers={**JSON, "Origin": "http://elsewhere.example"})
    assert r.status_code == 403
    r = client.post("/api/start", content="test=compression", headers={"Content-Type": "application/x-www-form-urlencoded"})
    assert r.status_code == 415


def test_a_token_guards_the_api_and_the_files_and_the_login_sets_it(tmp_path):
    _console, client = _client(tmp_path, token="s3cret")
    assert client.get("/").status_code == 200  # the page itself loads (and asks for the token)
    assert client.get("/api/status").status_code == 401
    assert client.get("/files/records/x.csv").status_code == 401
    assert client.post("/api/start", json={"test": "compression"}, headers=JSON).status_code == 401
    assert client.post("/api/login", json={"token": "wrong"}, headers=JSON).status_code == 401
    assert client.post("/api/login", json={"token": "s3cret"}, headers=JSON).status_code == 200
    assert client.get("/api/status").status_code == 200  # the cookie now
    assert TestClient(client.app, base_url=BASE_URL).get("/api/status", headers={"X-Flowcurve-Token": "s3cret"}).status_code == 200


def test_console_listening_beyond_the_loopback_makes_a_token(monkeypatch, tmp_path, capsys):
    seen = {}

    def fake_serve(console, host, port):
        seen["host"], seen["port"] = host, port

    import flowcurve.console.server as server

    monkeypatch.setattr(server, "serve", fake_serve)
    assert cli_main(["console", "--host", "0.0.0.0", "--port", "8099", "--out", str(tmp_path)]) == 0
    err = capsys.readouterr().err
    assert "access token" in err and seen == {"host": "0.0.0.0", "port": 8099}
    assert cli_main(["console", "--out", str(tmp_path)]) == 0
    assert "access token" not in capsys.readouterr().err


def test_fit_with_nothing_optional_names_every_missing_input_beside_its_field_and_writes_nothing(tmp_path):
    """The page's fit and card asked for one input per refused attempt (Poisson's ratio, then density,
    then specific heat; melting temperature, then m) and left a fits/fit-* folder each time."""
    _console, client = _client(tmp_path)
    names = identified_records(tmp_path / "out")
    r = client.post("/api/fit", json={"records": names, "format": "lsdyna"}, headers=JSON)
    assert r.status_code == 400, r.text
    body = r.json()
    assert set(body["fields"]) == {"melt_temp", "fix_C", "fix_m", "E_MPa", "poisson", "density", "cp", "fit"}
    for label in ("Melting temperature, °C", "fix C", "fix m", "E, MPa", "Poisson's ratio", "Density, kg/m³", "Specific heat, J/(kg K)"):
        assert label in body["error"], label
    assert "need 7 input(s)" in body["error"]
    assert not (tmp_path / "out" / "fits").exists() or not list((tmp_path / "out" / "fits").iterdir())
    # everything given: the fit and the card are written in one fits/fit-* folder
    r = client.post("/api/fit", json={"records": names, "format": "lsdyna", "melt_temp": "1450", "fix_C": "0.01", "fix_m": "1",
                                      "E_MPa": "200000", "poisson": "0.3", "density": "7850", "cp": "460"}, headers=JSON)
    assert r.status_code == 200, r.text
    assert len(list((tmp_path / "out" / "fits").iterdir())) == 1


def test_fit_form_values_the_service_refuses_are_tied_to_their_fields_without_reading_the_message(tmp_path):
    """A number that is none, an unknown format or method: the request's FieldError names the form
    field (issue 44); they came back as argparse's one line with no field."""
    _console, client = _client(tmp_path)
    names = identified_records(tmp_path / "out")
    r = client.post("/api/fit", json={"records": names, "format": "nastran", "melt_temp": "hot", "density": "1e", "method": "best"},
                    headers=JSON)
    assert r.status_code == 400, r.text
    fields = r.json()["fields"]
    assert set(fields) == {"melt_temp", "density", "format", "method"}, fields
    assert fields["melt_temp"] == "not a number: 'hot'" and fields["density"] == "not a number: '1e'"
    assert "invalid choice: 'nastran'" in fields["format"] and "invalid choice: 'best'" in fields["method"]
    assert not (tmp_path / "out" / "fits").exists() or not list((tmp_path / "out" / "fits").iterdir())


def test_the_fit_form_offers_the_registries_and_its_law_units_and_lsdyna_material_reach_the_card(tmp_path):
    """The console wrote only Johnson–Cook cards in mm-s-t-N-MPa with *MAT_015 and *MAT_024: the law, the
    unit system and the LS-DYNA material (224, the tabulated one) had no field (issue 45). /api/info lists
    them from the registries; the card written says what was chosen."""
    from flowcurve.identification.laws.base import registered_laws
    from flowcurve.reports.units import UNIT_SYSTEMS

    _console, client = _client(tmp_path)
    info = client.get("/api/info").json()
    assert [name for name, _ in info["laws"]][0] == "johnson_cook" and {n for n, _ in info["laws"]} == set(registered_laws())
    assert {u for u, _ in info["unit_systems"]} == set(UNIT_SYSTEMS) and [m for m, _ in info["lsdyna_materials"]] == ["", "15", "24", "224"]
    assert [m for m, _ in info["fit_methods"]] == ["global", "stepwise"]
    names = identified_records(tmp_path / "out")
    given = {"records": names, "format": "lsdyna", "melt_temp": "1450", "fix_C": "0.01", "fix_m": "1", "E_MPa": "200000",
             "poisson": "0.3", "density": "7850", "cp": "460"}
    r = client.post("/api/fit", json={**given, "law": "hensel_spitel", "lsdyna_material": "99"}, headers=JSON)
    assert r.status_code == 400, r.text
    fields = r.json()["fields"]
    assert "did you mean 'hensel_spittel'" in fields["law"] and "invalid choice: '99'" in fields["lsdyna_material"], fields
    r = client.post("/api/fit", json={**given, "law": "johnson_cook", "units": "mm-ms-kg-kN-GPa", "lsdyna_material": "224"}, headers=JSON)
    assert r.status_code == 200, r.text
    card = client.get(r.json()["card"]).text
    assert "*MAT_TABULATED_JOHNSON_COOK" in card and "*MAT_PIECEWISE_LINEAR_PLASTICITY" not in card
    assert "mm-ms-kg-kN-GPa" in card
