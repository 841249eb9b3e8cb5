"""The console in a real headless Chromium: a virtual compression test set up, run, watched,
stopped, annotated and identified through the page; the record compared with what
``flowcurve run`` writes; a reload, a closed browser and a second page during a test; a bad
value in the form. Every stage leaves a screenshot (see conftest.ARTIFACTS)."""

from __future__ import annotations

import json
import math
import time
import urllib.request

import pytest

from flowcurve.cli import main as cli_main
from flowcurve.record.format import read_record
from tests.console.conftest import BROWSER_TIME_SCALE, identified_records

By = pytest.importorskip("selenium.webdriver.common.by", reason="selenium is not installed (pip install -e .[test])").By

RUN_STATES = ("starting", "tare", "waiting", "recording")


def wait_for(predicate, timeout_s: float = 60.0, what: str = "condition", driver=None):
    end = time.monotonic() + timeout_s
    last = None
    while time.monotonic() < end:
        try:
            last = predicate()
            if last:
                return last
        except AssertionError:  # the page shows a failure: no use waiting
            raise
        except Exception as exc:  # the page is still loading: try again
            last = exc
        time.sleep(0.1)
    page = ""
    if driver is not None:
        page = (f"; page: state {text(driver, '#state')!r}, message {text(driver, '#message')!r}, form errors {text(driver, '#setup')[-300:]!r}, "
                f"post form {text(driver, '#post')[-300:]!r}, result {text(driver, '#result')[:300]!r}")
    raise AssertionError(f"timed out waiting for {what} (last: {last!r}){page}")


def text(driver, css: str) -> str:
    return driver.find_element(By.CSS_SELECTOR, css).text


def fd_points(driver) -> int:
    return int(driver.execute_script("return window.fcStats.fdPoints"))


def fill(driver, values: dict[str, str]) -> None:
    for name, value in values.items():
        el = driver.find_element(By.NAME, name)
        if el.tag_name == "select":
            driver.execute_script("arguments[0].value = arguments[1]; arguments[0].dispatchEvent(new Event('change'))", el, value)
        else:
            el.clear()
            el.send_keys(value)


def open_console(driver, url: str) -> None:
    driver.get(url)
    wait_for(lambda: driver.execute_script("return window.fcStats && window.fcStats.events") >= 1, what="the page to connect")


PLASTIC_SAMPLES = 200  # about 2 wall s at BROWSER_TIME_SCALE: hk about 6.6 mm of h0 7.0
SETUP = {"test": "compression", "material": "steel45", "E_MPa": "200000", "specimen_id": "C-browser", "operator": "selenium", "speed": "0.025"}  # about 25 wall seconds of loading


def test_a_compression_test_through_the_page_gives_runs_record_and_its_result(served_console, browser_factory, shot, tmp_path):
    driver = browser_factory()
    open_console(driver, served_console.url)
    assert text(driver, "#state") == "IDLE"  # CSS upper-cases the badge
    assert text(driver, "#heater") == "OFF"
    assert f"time ×{BROWSER_TIME_SCALE:g}" in text(driver, "#time-scale")  # the virtual rig's time scale is shown
    # placeholders cannot be taken for entered values: each in parentheses ("steel45", "room", "60" looked entered)
    holders = [el.get_attribute("placeholder") for el in driver.find_elements(By.CSS_SELECTOR, "input[placeholder]")]
    assert holders and all(h.startswith("(") and h.endswith(")") for h in holders), holders
    shot(driver, "1-idle")

    # a bad value: refused beside its field with run's words, nothing started
    fill(driver, {**SETUP, "d0": "-3"})
    driver.find_element(By.ID, "btn-start").click()
    error = wait_for(lambda: text(driver, '#setup .field-error[data-for="d0"]'), what="the d0 error")
    assert error == "d0, mm must be more than 0 and at most 30 mm (the largest diameter the grips and platens take, [frame] max_specimen_diameter_mm), got -3"
    assert "invalid" in driver.find_element(By.ID, "f-d0").get_attribute("class")
    assert served_console.console.runner.current is None
    shot(driver, "2-bad-input")

    fill(driver, {"d0": ""})
    driver.find_element(By.ID, "btn-start").click()
    wait_for(lambda: text(driver, "#state").lower() == "recording", what="recording", driver=driver)
    first = wait_for(lambda: fd_points(driver), what="first plot points", driver=driver)
    wait_for(lambda: fd_points(driver) > first + 10, what="the live plot to grow", driver=driver)
    # stop well past yield: the virtual specimen yields near sample 50 (0.5 wall s), and a stop
    # before it leaves hk = h0, which the identification rightly refuses (a CI run once stopped there)
    wait_for(lambda: served_console.console.runner.current.view.samples >= PLASTIC_SAMPLES, what=f"{PLASTIC_SAMPLES} samples", driver=driver)
    assert not text(driver, '#setup .field-error[data-for="d0"]')
    assert driver.find_element(By.ID, "btn-start").get_attribute("disabled") is not None
    shot(driver, "3-recording")

    driver.find_element(By.ID, "btn-stop").click()
    assert text(driver, "#message").startswith("Stop asked")  # Stop says what it asked for at once
    wait_for(lambda: text(driver, "#state").lower() == "complete", what="complete")
    assert "state-complete" in driver.find_element(By.ID, "state").get_attribute("class")
    outcome = wait_for(lambda: text(driver, "#outcome"), what="the outcome")
    assert "complete — operator stop (console)" in outcome
    # every recorded sample is a point of the live plot (1832 points for 1841 samples before)
    run = served_console.console.runner.current
    wait_for(lambda: fd_points(driver) == run.outcome.samples, timeout_s=10, what=f"{run.outcome.samples} plot points (page has {fd_points(driver)})")
    assert int(text(driver, "#fd-count")) == run.outcome.samples == len(read_record(run.record).data)
    shot(driver, "4-stopped")

    # post-test measurements: the virtual rig's own measurement of the stopped specimen, typed in
    run = served_console.console.runner.current
    measured = dict(run.outcome.post)
    assert set(measured) == {"post.hk_mm", "post.dmax_mm"}
    typed = {k: f"{v:.4f}" for k, v in measured.items()}
    fill(driver, typed)
    driver.find_element(By.ID, "btn-post").click()
    figures = wait_for(lambda: _result_or_error(driver), timeout_s=120, what="the identified result", driver=driver)
    assert "friction coefficient μ" in figures and "Johnson–Cook A, MPa" in figures
    assert "_MPa" not in figures and "friction_mu" not in figures  # words and units, not raw keys
    links = [a.get_attribute("href") for a in driver.find_elements(By.CSS_SELECTOR, "#result a")]
    assert any(h.endswith("/result.json") for h in links)
    shot(driver, "5-result")

    # the record: amended with what was typed, identical in content to run's
    rec = read_record(run.record)
    assert {k: float(rec.meta[k]) for k in typed} == {k: float(v) for k, v in typed.items()}
    result_json = urllib.request.urlopen(served_console.url + "files/results/" + run.record.stem + "/result.json").read()
    assert b'"friction_mu"' in result_json
    reference_path = tmp_path / "run.csv"
    assert cli_main(["run", "compression", "--quiet", "--out", str(reference_path), "--time-scale", str(BROWSER_TIME_SCALE),
                     "--material", "steel45", "--E", "200000", "--specimen-id", "C-browser", "--operator", "selenium", "--speed", SETUP["speed"]]) == 0
    ref = read_record(reference_path)
    assert list(rec.data.columns) == list(ref.data.columns)
    # what the rig lost is declared and varies with the machine's load (the virtual amplifier skips frames on a busy PC)
    losses = {"samples_missing", "stream_restarts", "readings_rejected", "data_loss"}
    # the measured speed is stated once the crosshead travelled 1 mm: the page's test is stopped sooner than run's
    travel = {"crosshead_speed_measured_mm_per_s", "instruments.crosshead_stamp_u_s"}  # and the encoder stamps' u: the host's load
    assert set(rec.meta) - {"stop_reason"} - losses - travel == set(ref.meta) - {"stop_reason"} - losses - travel
    varying = {"date", "stop_reason", "samples", "post.hk_mm", "post.dmax_mm", *losses, *travel}  # the time, where each test stopped
    assert {k: v for k, v in rec.meta.items() if k not in varying} == {k: v for k, v in ref.meta.items() if k not in varying}
    declared = {"data_loss", "frames_missing", "stream_restart", "retry", "late_reply", "dropped"}
    assert [e.name for e in rec.events if e.name not in declared] == [e.name for e in ref.events if e.name not in declared]
    assert int(rec.meta["samples"]) == len(rec.data)

    # the records list: select it, fit, download the card
    driver.find_element(By.ID, "btn-refresh").click()
    wait_for(lambda: "Johnson–Cook A, MPa" in text(driver, "#records tbody"), what="the record and its result in the list")
    box = f'#records input[value="{run.record.name}"]'
    wait_for(lambda: driver.find_element(By.CSS_SELECTOR, box).click() or driver.find_element(By.CSS_SELECTOR, box).is_selected(), what="the record selected")
    fill(driver, {"melt_temp": "1450", "fix_C": "0.01", "fix_m": "1", "poisson": "0.3", "density": "7850", "cp": "460", "format": "lsdyna"})
    # the law, unit-system and LS-DYNA-material choices come from /api/info: the tabulated Johnson–Cook in kN and GPa
    assert [o.get_attribute("value") for o in driver.find_elements(By.CSS_SELECTOR, "#fit-lsdyna option")] == ["", "15", "24", "224"]
    fill(driver, {"law": "johnson_cook", "units": "mm-ms-kg-kN-GPa", "lsdyna_material": "224"})
    driver.find_element(By.ID, "btn-fit").click()
    card = wait_for(lambda: driver.find_element(By.ID, "card-link"), timeout_s=120, what="the card link")
    body = urllib.request.urlopen(card.get_attribute("href")).read().decode()
    assert "*MAT_TABULATED_JOHNSON_COOK" in body and "mm-ms-kg-kN-GPa" in body
    shot(driver, "6-records-fit")


def _result_or_error(driver) -> str:
    """The result's figures once shown; an identification error shown instead fails at once."""
    errors = driver.find_elements(By.ID, "result-error")
    if errors and errors[0].text:
        raise AssertionError(f"the page shows {errors[0].text!r}")
    return text(driver, "#result-figures")


def shown_figures(driver) -> dict[str, float]:
    """The identified figures as the page shows them (four significant digits), by result.json key."""
    out = {}
    for div in driver.find_elements(By.CSS_SELECTOR, "#result-figures div"):
        out[div.get_attribute("data-key")] = float(div.find_element(By.TAG_NAME, "b").text)
    return out


def test_a_tension_test_to_fracture_then_the_post_test_form_gives_the_result(served_console, browser_factory, shot):
    driver = browser_factory()
    open_console(driver, served_console.url)
    fill(driver, {**SETUP, "test": "tension", "specimen_id": "T-browser", "speed": ""})  # the virtual run's speed: about 14 wall s
    assert driver.find_element(By.ID, "f-l0").is_displayed() and driver.find_element(By.ID, "f-lc").is_displayed()  # the tension fields show
    driver.find_element(By.ID, "btn-start").click()
    wait_for(lambda: text(driver, "#state").lower() == "recording", what="recording", driver=driver)
    wait_for(lambda: fd_points(driver) > 20, what="the live plot", driver=driver)
    shot(driver, "1-recording")
    wait_for(lambda: text(driver, "#state").lower() == "complete", timeout_s=180, what="the fracture", driver=driver)
    outcome = wait_for(lambda: text(driver, "#outcome"), what="the outcome", driver=driver)
    assert "complete — fracture" in outcome

    # the post-test form asks for lu, dk, du and the neck radius, in run's words
    run = served_console.console.runner.current
    post_form = text(driver, "#post-fields")
    for words in ("gauge length after fracture lu [mm]", "diameter at fracture dk [mm]", "diameter in the uniform part du [mm]", "neck profile radius [mm]"):
        assert words in post_form
    # what an operator reads with calipers on the broken specimen: the virtual rig's values to 0.01 mm
    measured = dict(run.outcome.post)
    assert set(measured) == {"post.lu_mm", "post.dk_mm", "post.du_mm", "post.neck_radius_mm"}
    typed = {k: f"{v:.2f}" for k, v in measured.items()}
    fill(driver, typed)
    shot(driver, "2-post-form")
    driver.find_element(By.ID, "btn-post").click()
    wait_for(lambda: "Johnson–Cook A, MPa" in text(driver, "#result-figures"), timeout_s=120, what="the identified result", driver=driver)
    shot(driver, "3-result")

    # the record keeps what was typed; the result follows from it in closed form
    rec = read_record(run.record)
    assert {k: float(rec.meta[k]) for k in typed} == {k: float(v) for k, v in typed.items()}  # (34.90 is kept as 34.9)
    l0, d0 = float(rec.meta["specimen.l0_mm"]), float(rec.meta["specimen.d0_mm"])
    lu, dk, radius = (float(typed[k]) for k in ("post.lu_mm", "post.dk_mm", "post.neck_radius_mm"))
    expected = {"A_pct": (lu - l0) / l0 * 100.0, "Z_pct": (1.0 - (dk / d0) ** 2) * 100.0}  # A = Δl/l0, Z = ΔS/S0
    result = json.loads(urllib.request.urlopen(served_console.url + "files/results/" + run.record.stem + "/result.json").read())
    for name, value in expected.items():
        assert result[name] == pytest.approx(value, rel=1e-12)
    a_over_R = dk / 2.0 / radius
    neck = result["neck_corrections"]
    assert neck["a_over_R_source"] == "measured neck radius" and neck["a_over_R"] == pytest.approx(a_over_R, rel=1e-12)
    # Bridgman's factor 1 / ((1 + 2R/a) ln(1 + a/2R)) from the typed dk and neck radius
    assert neck["bridgman"]["factor"] == pytest.approx(1.0 / ((1.0 + 2.0 / a_over_R) * math.log1p(a_over_R / 2.0)), rel=1e-9)
    shown = shown_figures(driver)
    for name, value in expected.items():
        assert shown[name] == pytest.approx(value, rel=5e-4)  # the page rounds to four digits
    assert shown["JC A_MPa"] > 0 and shown["Rm_MPa"] > shown["Rp02_MPa"]


def test_reload_close_and_a_second_page_during_a_test(served_console, browser_factory, shot):
    first = browser_factory()
    open_console(first, served_console.url)
    fill(first, {**SETUP, "specimen_id": "C-reload", "speed": "0.01"})  # slow: the test outlasts the browsers coming and going
    first.find_element(By.ID, "btn-start").click()
    wait_for(lambda: fd_points(first) > 5, what="points on the first page")

    # a second page (a tablet-sized one) sees the running test, its points included
    second = browser_factory(820, 1180)
    open_console(second, served_console.url)
    wait_for(lambda: text(second, "#state").lower() == "recording", what="the second page to see the test")
    wait_for(lambda: fd_points(second) > 5, what="points on the second page")
    assert second.find_element(By.ID, "btn-start").get_attribute("disabled") is not None
    shot(second, "1-second-page-tablet")

    # a reload picks the live state up again
    before = fd_points(first)
    first.refresh()
    wait_for(lambda: text(first, "#state").lower() == "recording", what="the reloaded page's state")
    wait_for(lambda: fd_points(first) >= before, what="the reloaded page's points")
    shot(first, "2-after-reload")

    # the first browser closes: the test goes on recording
    run = served_console.console.runner.current
    first.quit()
    samples = run.view.samples
    wait_for(lambda: run.view.samples > samples + 20, what="recording after the browser closed")
    assert run.running
    seen = fd_points(second)
    wait_for(lambda: fd_points(second) > seen, what="the second page still updating")
    second.find_element(By.ID, "btn-stop").click()
    wait_for(lambda: text(second, "#state").lower() == "complete", what="complete on the second page")
    shot(second, "3-stopped-from-second-page")
    rec = read_record(run.record)
    assert rec.meta["status"] == "complete" and rec.meta["specimen.id"] == "C-reload"
    assert len(rec.data) == run.outcome.samples


def test_heating_shows_the_heater_on_and_an_abort_switches_it_off(served_console, browser_factory, shot):
    driver = browser_factory()
    open_console(driver, served_console.url)
    fill(driver, {**SETUP, "specimen_id": "C-hot", "temperature": "300", "soak": "30"})
    driver.find_element(By.ID, "btn-start").click()
    wait_for(lambda: text(driver, "#state").lower() == "heating", what="heating")
    wait_for(lambda: text(driver, "#heater") == "ON", what="the heater badge on")
    start_points = wait_for(lambda: int(driver.execute_script("return window.fcStats.ttPoints")), what="temperature points")
    wait_for(lambda: int(driver.execute_script("return window.fcStats.ttPoints")) > start_points + 5, what="the temperature plot to grow")
    shot(driver, "1-heating")
    run = served_console.console.runner.current  # (the controller switches the relay on and off: the badge follows it)
    driver.find_element(By.ID, "btn-abort").click()
    driver.switch_to.alert.accept()
    wait_for(lambda: text(driver, "#state").lower() == "aborted", what="aborted after the abort")  # an abort is not "done"
    assert "state-aborted" in driver.find_element(By.ID, "state").get_attribute("class")
    assert "aborted" in driver.find_element(By.ID, "message").get_attribute("class")
    assert text(driver, "#heater") == "OFF" and run.heater_source.relay_on is False
    assert "aborted" in text(driver, "#message")
    # nothing reads the furnace after the test: its last temperature is marked stale, not shown as live
    note = wait_for(lambda: text(driver, "#stale"), timeout_s=10, what="the readings marked stale")
    assert "as of the end of the test" in note and "may still be hot" in note, note
    assert "stale" in driver.find_element(By.CSS_SELECTOR, ".readings").get_attribute("class")
    shot(driver, "2-aborted")
    assert "# status: aborted\n" in run.record.read_text()


def test_a_device_fault_is_named_as_run_names_it(served_console, browser_factory, shot):
    rigs = []
    served_console.console.runner.virtual_setup = rigs.append
    driver = browser_factory()
    open_console(driver, served_console.url)
    fill(driver, {**SETUP, "specimen_id": "C-fault", "speed": "0.02"})
    driver.find_element(By.ID, "btn-start").click()
    wait_for(lambda: fd_points(driver) > 20, what="recording")
    rigs[0].inject("encoder", "unplug")
    wait_for(lambda: text(driver, "#state").lower() == "failed", what="the failed state")
    run = served_console.console.runner.current
    # run prints "flowcurve: error: <the error> (the record keeps everything up to the fault)"
    assert text(driver, "#message") == f"{run.outcome.error} (the record keeps everything up to the fault)"
    assert "crosshead encoder" in text(driver, "#message")
    assert "failed" in driver.find_element(By.ID, "message").get_attribute("class")
    assert "state-failed" in driver.find_element(By.ID, "state").get_attribute("class")
    shot(driver, "1-fault")
    rec = read_record(run.record)
    assert rec.meta["status"] == "aborted" and len(rec.data) > 0


def test_a_console_with_a_token_asks_for_it_before_showing_anything(served_console, browser_factory, shot):
    served_console.console.token = "lab-PC-7f3a"  # as when listening beyond the loopback
    driver = browser_factory()
    driver.get(served_console.url)
    dialog = wait_for(lambda: driver.find_element(By.ID, "token-dialog").is_displayed() and driver.find_element(By.ID, "token-dialog"), what="the token dialog")
    assert text(driver, "#heater") == "UNKNOWN" and driver.execute_script("return window.fcStats.events") == 0  # no stream yet: nothing claimed
    driver.find_element(By.ID, "token").send_keys("guess")
    dialog.find_element(By.CSS_SELECTOR, "button").click()
    assert wait_for(lambda: text(driver, "#token-error"), what="the refusal") == "wrong token"
    shot(driver, "1-token-refused")
    field = driver.find_element(By.ID, "token")
    field.clear()
    field.send_keys("lab-PC-7f3a")
    dialog.find_element(By.CSS_SELECTOR, "button").click()
    wait_for(lambda: not driver.find_element(By.ID, "token-dialog").is_displayed(), what="the dialog to close")
    wait_for(lambda: driver.execute_script("return window.fcStats.events") >= 1, what="the live stream")
    assert "virtual rig" in text(driver, "#rig")
    shot(driver, "2-token-accepted")


def test_the_heater_badge_and_heating_progress_at_time_scale_60(served_console, browser_factory, shot):
    """The heater badge read "off" in 4 of 8 polls while the furnace heated at time scale 60 (its relay
    pulses within a 33 ms wall period); the heating progress and the time scale were not shown."""
    served_console.console.time_scale = 60.0
    driver = browser_factory()
    open_console(driver, served_console.url)
    fill(driver, {**SETUP, "specimen_id": "C-heat60", "temperature": "300", "soak": "30"})
    driver.find_element(By.ID, "btn-start").click()
    wait_for(lambda: text(driver, "#state").lower() == "heating", what="heating", driver=driver)
    seen, progress = [], []
    while text(driver, "#state").lower() == "heating" and len(seen) < 24:
        seen.append(text(driver, "#heater"))
        progress.append(float(driver.find_element(By.ID, "heat-progress").get_attribute("value")))
        if len(seen) == 6:
            shot(driver, "1-heating-progress")
        time.sleep(0.25)
    assert len(seen) >= 8, f"only {len(seen)} polls while heating"
    assert seen == ["ON"] * len(seen), seen
    assert progress[-1] > progress[0] and 0 <= min(progress) and max(progress) <= 1
    assert "heating to 300 °C" in text(driver, "#heat-progress-text") or text(driver, "#state").lower() != "heating"
    assert "time ×60" in text(driver, "#time-scale")
    served_console.console.runner.abort()
    wait_for(lambda: text(driver, "#state").lower() == "aborted", what="aborted")


def test_a_console_that_shuts_down_leaves_the_page_disabled_and_saying_what_to_do(served_console, browser_factory, shot):
    """After the console was killed the page kept a blue RECORDING badge with Stop and Abort enabled."""
    driver = browser_factory()
    open_console(driver, served_console.url)
    fill(driver, {**SETUP, "specimen_id": "C-lost", "speed": "0.01"})
    driver.find_element(By.ID, "btn-start").click()
    wait_for(lambda: fd_points(driver) > 5, what="recording", driver=driver)
    assert driver.find_element(By.ID, "btn-stop").get_attribute("disabled") is None
    run = served_console.console.runner.current
    served_console.console.close()  # what SIGTERM or Ctrl-C does: abort the test, end the streams
    served_console.server.should_exit = True
    served_console.thread.join(30)
    assert not served_console.thread.is_alive()
    wait_for(lambda: text(driver, "#state").lower() == "connection lost", timeout_s=15, what="the lost connection shown", driver=driver)
    for button in ("btn-start", "btn-stop", "btn-abort"):
        assert driver.find_element(By.ID, button).get_attribute("disabled") is not None, button
    message = text(driver, "#message")
    assert "start it again (flowcurve console) and reload this page" in message, message
    assert "off until it is back" in message
    assert text(driver, "#heater") == "UNKNOWN"
    wait_for(lambda: "no connection" in text(driver, "#stale"), timeout_s=10, what="the readings marked stale")
    assert read_record(run.record).meta["status"] == "aborted"
    shot(driver, "1-connection-lost")


def test_values_outside_the_rig_and_a_fit_with_nothing_given_are_named_at_once_beside_their_fields(served_console, browser_factory, shot):
    """-300 °C, 1e9 mm/s and a 1e12 mm target were accepted; the fit form asked for one missing input per attempt."""
    driver = browser_factory()
    open_console(driver, served_console.url)
    fill(driver, {**SETUP, "temperature": "-300", "speed": "1e9", "target": "1e12"})
    driver.find_element(By.ID, "btn-start").click()
    wait_for(lambda: text(driver, '#setup .field-error[data-for="target"]'), what="the range errors")
    assert text(driver, '#setup .field-error[data-for="temperature"]').startswith("Temperature, °C must be above 20 C (room")
    assert text(driver, '#setup .field-error[data-for="speed"]').startswith("Speed, mm/s must be between 0.001 and 2 mm/s")
    assert text(driver, '#setup .field-error[data-for="target"]').startswith("Target, mm must be more than 0 and at most 250 mm")
    assert served_console.console.runner.current is None and text(driver, "#state") == "IDLE" and text(driver, "#record-name") == ""
    shot(driver, "1-out-of-range")

    # two identified records at one temperature and one rate, nothing typed in the fit form
    names = identified_records(served_console.console.workspace.root)
    driver.find_element(By.ID, "btn-refresh").click()
    for name in names:
        box = f'#records input[value="{name}"]'
        wait_for(lambda: driver.find_element(By.CSS_SELECTOR, box).click() or driver.find_element(By.CSS_SELECTOR, box).is_selected(), what=f"{name} selected")
    driver.find_element(By.ID, "btn-fit").click()
    summary = wait_for(lambda: text(driver, '#fit .field-error[data-for="fit"]'), timeout_s=60, what="the fit's refusal")
    assert "need 7 input(s) not given" in summary, summary
    for field in ("melt_temp", "fix_C", "fix_m", "E_MPa", "poisson", "density", "cp"):
        assert text(driver, f'#fit .field-error[data-for="{field}"]').startswith("needed"), field
        assert "invalid" in driver.find_element(By.CSS_SELECTOR, f'#fit [name="{field}"]').get_attribute("class"), field
    assert not (served_console.console.workspace.fits.exists() and list(served_console.console.workspace.fits.iterdir()))
    shot(driver, "2-fit-missing-inputs")


def test_a_killed_console_leaves_the_page_disabled_and_saying_what_to_do(browser_factory, shot, tmp_path):
    """The console killed outright (no last word): the page kept a blue RECORDING badge with Stop and Abort enabled."""
    import signal
    import socket
    import subprocess
    import sys

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    proc = subprocess.Popen([sys.executable, "-m", "flowcurve", "console", "--out", str(tmp_path / "out"), "--port", str(port),
                             "--time-scale", str(BROWSER_TIME_SCALE)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        url = f"http://127.0.0.1:{port}/"
        wait_for(lambda: urllib.request.urlopen(url + "api/info", timeout=1).read(), what="the console to answer")
        driver = browser_factory()
        open_console(driver, url)
        fill(driver, {**SETUP, "specimen_id": "C-killed", "speed": "0.01"})
        driver.find_element(By.ID, "btn-start").click()
        wait_for(lambda: fd_points(driver) > 5, what="recording", driver=driver)
        proc.send_signal(signal.SIGKILL)
        proc.wait(30)
        wait_for(lambda: text(driver, "#state").lower() == "connection lost", timeout_s=15, what="the lost connection shown", driver=driver)
        for button in ("btn-start", "btn-stop", "btn-abort"):
            assert driver.find_element(By.ID, button).get_attribute("disabled") is not None, button
        assert "start it again (flowcurve console) and reload this page" in text(driver, "#message")
        wait_for(lambda: "no connection" in text(driver, "#stale"), timeout_s=10, what="the readings marked stale")
        shot(driver, "1-killed")
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()


def test_the_fault_drill_field_on_the_virtual_rig(served_console, browser_factory, shot):
    """Issue 31: the set-up form offers run's --fault on the virtual rig, with the kinds per device;
    a bad drill is named beside its field and starts nothing; a good one runs and is declared."""
    driver = browser_factory()
    open_console(driver, served_console.url)
    wait_for(lambda: driver.find_element(By.ID, "fault-row").is_displayed(), what="the fault drill field")
    assert "relay_stuck [furnace]" in text(driver, "#fault-hint")
    fill(driver, {**SETUP, "specimen_id": "C-drill", "speed": "0.2", "fault": "loadcell:melt"})
    driver.find_element(By.ID, "btn-start").click()
    error = wait_for(lambda: text(driver, '#setup .field-error[data-for="fault"]'), what="the drill's refusal")
    assert error.startswith("Fault drill 'loadcell:melt': unknown fault 'melt'") and "relay_stuck" in error
    assert served_console.console.runner.current is None
    shot(driver, "1-bad-drill")
    fill(driver, {"fault": "encoder:corrupt@2"})
    driver.find_element(By.ID, "btn-start").click()
    wait_for(lambda: text(driver, "#state").lower() in ("complete", "aborted", "failed"), timeout_s=120, what="the end of the test")
    rec = read_record(served_console.console.runner.current.record)
    assert rec.meta["virtual.faults"] == "encoder:corrupt:50@2"
    assert any(e.name == "corrupt" and e.text.startswith("crosshead encoder") for e in rec.events)


def test_start_stays_off_while_the_page_is_connecting(served_console, browser_factory, shot):
    """Issue 42: until the event stream has told the rig's state and heater, Start is off (and a
    submitted form starts nothing); once the state is known, Start is on. Failed on the old page:
    Start was enabled while the badge said 'connecting'."""
    driver = browser_factory()
    driver.execute_cdp_cmd("Network.enable", {})
    driver.execute_cdp_cmd("Network.setBlockedURLs", {"urls": ["*/api/events*"]})  # the state never arrives
    driver.get(served_console.url)
    wait_for(lambda: text(driver, "#rig").startswith("—"), what="the page to boot (/api/info answered)")
    time.sleep(1.0)  # the blocked stream has failed by now
    assert text(driver, "#state").lower() == "connecting" and text(driver, "#heater").lower() == "unknown"
    assert driver.find_element(By.ID, "btn-start").get_attribute("disabled") is not None
    driver.execute_script("document.querySelector('#setup').requestSubmit()")  # Enter in a field, a script
    time.sleep(0.5)
    assert served_console.console.runner.current is None  # nothing was started
    shot(driver, "1-connecting-start-off")
    driver.execute_cdp_cmd("Network.setBlockedURLs", {"urls": []})
    driver.refresh()
    wait_for(lambda: text(driver, "#state").lower() == "idle", what="the state to arrive", driver=driver)
    assert driver.find_element(By.ID, "btn-start").get_attribute("disabled") is None
