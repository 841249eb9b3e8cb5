"""Issue 42's fault rows through the independent injector (pty_injector.py): ``flowcurve rig
virtual`` in one process, ``flowcurve run`` in another, the injector between them on ptys. Each
faulty run must end as README's fault table says (exit code, the device named, the heater off,
the event in the record) and what survived must match a fault-free run of the same test through
the same injector: the force at every crosshead position from 0.5 to 2.9 mm within 1 %, the last
crosshead within 0.05 mm, Fm within 0.3 %, Rm from identify within 1 %.

Real time (``-m pty``): a tension test to 3 mm at time scale :data:`TIME_SCALE` (about
:data:`TIME_SCALE`/100 model seconds a frame: a few hundred rows in about ten host seconds).
"""

from __future__ import annotations

import contextlib
import io
import json
import re
import tomllib
from dataclasses import dataclass

import numpy as np
import pytest

from .pty_injector import Injector, Link, Rule, Terminated, aed_ascii_add, dcon_readdress, with_port
from .test_fault_drills import HEAT, RigProcess, Run, env, run_test, watchdog_switched_off  # noqa: F401 - env is a fixture

pytestmark = pytest.mark.pty

TIME_SCALE = 30.0
TARGET_MM = 3.0
FORCE_WINDOW_MM = (0.5, 2.9)
FORCE_TOL = 0.01
LAST_CROSSHEAD_TOL_MM = 0.05
FM_TOL = 0.003
ENCODER_COUNT_MM = 0.01  # the virtual crosshead encoder's 100 counts/mm
RM_TOL = 0.01
SPIKE_N = 900.0  # under 1 % of the 100 kN capacity


@dataclass
class Injected:
    """The rig process seen through the injector: what ``run_test`` needs (config, time scale, motor)."""

    rig: RigProcess
    injector: Injector
    config: object
    time_scale: float

    def motor(self):
        self.rig.motor()
        self.injector.mark()  # the rules' start_s count from the crosshead start


def links(config_text: str, rules: dict[str, list[Rule]], seed: int) -> dict[str, Link]:
    """A link for each device of the rig's configuration (AED ASCII frames end CR LF, DCON CR)."""
    conf = tomllib.loads(config_text)
    fmt = conf["loadcell"].get("output_format", 3)
    assert fmt in (1, 3, 5, 7, 9, 11), f"the injector's load-cell frames are ASCII here, not COF {fmt}"
    made = {"loadcell": Link("loadcell", conf["loadcell"]["port"], to_host=Terminated(b"\r\n"),
                             rules=rules.get("loadcell", ()), seed=seed)}
    for name in ("encoder", "furnace"):
        if name in conf:
            made[name] = Link(name, conf[name]["port"], to_host=Terminated(b"\r"), to_device=Terminated(b"\r"),
                              rules=rules.get(name, ()), seed=seed)
    return made


def injected_run(tmp_path, env, rules: dict[str, list[Rule]], *args, name: str, seed: int = 42):
    """One tension test to :data:`TARGET_MM` through the injector; (Run, injector, identify's result or its error)."""
    folder = tmp_path / name
    folder.mkdir()
    rig = RigProcess(folder, env, time_scale=TIME_SCALE)
    try:
        text = rig.config.read_text()
        with Injector(links(text, rules, seed), marked=False) as injector:
            config = folder / "injected.toml"
            config.write_text(with_port(text, injector.ports))
            run = run_test(folder, env, Injected(rig, injector, config, TIME_SCALE), "--target", TARGET_MM, *args,
                           out=folder / "r.csv")
        if run.code == 3 and "furnace" in run.err:  # the heater left to the module's watchdog: let it speak
            with contextlib.suppress(AssertionError):
                watchdog_switched_off(rig)
    finally:
        err = rig.stop()
    assert "Traceback" not in err, err
    return run, injector, rig, identify(folder / "r.csv", folder / "results")


def identify(record, out) -> dict | str:
    """``flowcurve identify`` with the material's handbook modulus (a few hundred rows do not resolve E)."""
    from flowcurve.cli import main
    from flowcurve.rig.virtual.materials import MATERIALS

    buf = io.StringIO()
    with contextlib.redirect_stdout(buf), contextlib.redirect_stderr(buf):
        code = main(["identify", str(record), "--out", str(out), "--no-plots", "--E", f"{MATERIALS['steel45'].E_MPa:g}"])
    result = out / record.stem / "result.json"
    return json.loads(result.read_text()) if code == 0 and result.exists() else buf.getvalue().strip()[-300:]


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """The fault-free test through the same injector (no rule); tried twice, since it is the truth
    and not what is tested (a starved machine may stop a real-time run: each try's end is shown)."""
    import os

    tmp = tmp_path_factory.mktemp("reference")
    lock_dir = tmp / "locks"
    lock_dir.mkdir()
    environ = {**os.environ, "MPLBACKEND": "Agg", "FLOWCURVE_LOCK_DIR": str(lock_dir)}
    ends = []
    for attempt in range(2):
        run, _, _, result = injected_run(tmp, environ, {}, name=f"reference{attempt}")
        ends.append((run.code, run.err.strip()[-200:]))
        if run.code in (0, 5) and run.record.meta["status"] == "complete":
            break
    assert run.code in (0, 5) and run.record.meta["status"] == "complete", ends
    assert isinstance(result, dict), f"identify refused the fault-free record: {result}"
    return run, result


# -- the numbers that survived ----------------------------------------------------------------------


def force_at_crosshead(run: Run, x_mm: np.ndarray) -> np.ndarray:
    """Force interpolated at crosshead positions (the rising part: crosshead moves forward)."""
    x = run.record.column("crosshead_mm")
    f = run.record.column("force_N")
    ok = np.isfinite(x) & np.isfinite(f)
    x, f = x[ok], f[ok]
    order = np.argsort(x, kind="stable")
    return np.interp(x_mm, x[order], f[order])


def fm_and_its_truth(run: Run, ref: Run) -> tuple[float, float, float]:
    """(Fm, its truth, slack N). A test that stops at the target with the force still rising has its Fm
    at the stop: its truth is the fault-free run's force at the same crosshead (continued along its
    last 0.1 mm where the run stopped further on), known to one encoder count of crosshead on either
    record (the slack); elsewhere the fault-free run's Fm, no slack."""
    x, f = (run.record.column(c) for c in ("crosshead_mm", "force_N"))
    x_ref = ref.record.column("crosshead_mm")
    i, end = int(np.nanargmax(f)), float(np.nanmax(x_ref))
    fm = float(f[i])
    if float(x[i]) < float(np.nanmax(x)) - ENCODER_COUNT_MM:  # a maximum before the stop
        return fm, float(np.nanmax(ref.record.column("force_N"))), 0.0
    at_end, before = force_at_crosshead(ref, np.array([end, end - 0.1]))
    slope = (at_end - before) / 0.1  # N/mm on the rising curve at the reference's stop
    truth = float(force_at_crosshead(ref, np.array([min(float(x[i]), end)]))[0]) + slope * max(0.0, float(x[i]) - end)
    return fm, truth, abs(slope) * ENCODER_COUNT_MM


def survived(run: Run, result, ref: Run, ref_result: dict) -> list[str]:
    """What is beyond tolerance against the fault-free run: [] when everything held."""
    bad = []
    grid = np.linspace(*FORCE_WINDOW_MM, 97)
    f, f_ref = force_at_crosshead(run, grid), force_at_crosshead(ref, grid)
    dev = np.abs(f / f_ref - 1.0)  # |F(x)/F_ref(x) − 1| at the same crosshead x
    if dev.max() > FORCE_TOL:
        bad.append(f"force at the same crosshead off by {100 * dev.max():.2f} % at {grid[dev.argmax()]:.2f} mm")
    x, x_ref = np.nanmax(run.record.column("crosshead_mm")), np.nanmax(ref.record.column("crosshead_mm"))
    if abs(x - x_ref) > LAST_CROSSHEAD_TOL_MM:
        bad.append(f"last crosshead {x:.3f} mm for {x_ref:.3f}")
    fm, fm_ref, slack = fm_and_its_truth(run, ref)
    if abs(fm - fm_ref) > FM_TOL * fm_ref + slack:
        bad.append(f"Fm {fm:.0f} N for {fm_ref:.0f} ({100 * (fm / fm_ref - 1):+.2f} %)")
    if not isinstance(result, dict):
        bad.append(f"identify refused: {result}")
    elif abs(result["Rm_MPa"] / ref_result["Rm_MPa"] - 1) > RM_TOL:
        bad.append(f"Rm {result['Rm_MPa']:.1f} MPa for {ref_result['Rm_MPa']:.1f} "
                   f"({100 * (result['Rm_MPa'] / ref_result['Rm_MPa'] - 1):+.2f} %)")
    return bad


def load_cell_named(run: Run, *events: str) -> str:
    texts = [f"{e.name} {e.text}" for e in run.record.events if e.name in events]
    assert any("load cell" in t for t in texts), [f"{e.name} {e.text}" for e in run.record.events]
    assert "load cell" in run.err
    return " ".join(texts)


def ended_complete_with_losses(run: Run):
    assert run.code == 5, (run.code, run.err)
    assert run.record.meta["status"] == "complete" and run.events("stop")
    assert "data_loss" in run.record.meta and run.events("data_loss")


# -- the rows ---------------------------------------------------------------------------------------


def test_reference_run_is_whole(reference):
    """The reference itself: nothing injected, a complete record reaching the target."""
    run, result = reference
    assert abs(np.nanmax(run.record.column("crosshead_mm")) - TARGET_MM) < LAST_CROSSHEAD_TOL_MM
    assert len(run.record.data) > 200 and result["Rm_MPa"] > 0


def test_drop_20_percent_of_the_frames_from_1_s(tmp_path, env, reference):
    run, inj, _, result = injected_run(tmp_path, env, {"loadcell": [Rule("to_host", "drop", rate=0.2, start_s=1.0)]},
                                       name="drop20")
    ended_complete_with_losses(run)
    load_cell_named(run, "frames_missing", "data_loss", "stream_restart")
    assert inj.links["loadcell"].rules[0].hits > 50
    bad = survived(run, result, *reference)
    assert not bad, bad


def test_drop_5_percent_of_the_frames(tmp_path, env, reference):
    run, inj, _, result = injected_run(tmp_path, env, {"loadcell": [Rule("to_host", "drop", rate=0.05)]}, name="drop5")
    ended_complete_with_losses(run)
    load_cell_named(run, "frames_missing", "data_loss", "stream_restart")
    bad = survived(run, result, *reference)
    assert not bad, bad


def test_garble_half_a_percent_of_the_bytes_costs_about_those_frames(tmp_path, env, reference):
    rule = Rule("to_host", "garble", rate=0.005, per="byte", start_s=0.5)
    run, inj, _, result = injected_run(tmp_path, env, {"loadcell": [rule]}, name="garble")
    ended_complete_with_losses(run)
    load_cell_named(run, "frames_missing", "data_loss", "stream_restart", "corrupt")
    # a garbled byte costs its frame (two when it was the CR LF between them), not a stream restart's many
    missing = int(run.record.meta.get("samples_missing", 0))
    assert missing <= 2 * rule.hits + 5, (missing, rule.hits, run.record.meta.get("data_loss"))
    bad = survived(run, result, *reference)
    assert not bad, bad


def test_one_frame_900_N_high_is_rejected_and_never_fm(tmp_path, env, reference):
    ref, _ = reference
    t = ref.record.column("time_s")
    at_s = 0.8 * (t[-1] - t[0]) / TIME_SCALE  # host seconds after the motor start: in the plastic range, near Fm
    counts = int(round(SPIKE_N / 100_000.0 * 1_000_000))  # COF 3: nominal 100 kN reads 1 000 000
    rule = Rule("to_host", "corrupt", count=1, start_s=at_s, transform=aed_ascii_add(counts),
                match=rb"^[+-]\d{7}\r\n$")
    run, inj, _, result = injected_run(tmp_path, env, {"loadcell": [rule]}, name="spike")
    assert rule.hits == 1 and inj.hits[0].after != inj.hits[0].before
    assert run.code == 5, (run.code, run.err)  # a reading rejected: named, exit 5
    named = [f"{e.name} {e.text}" for e in run.record.events if re.search(r"spike|reject|corrupt", f"{e.name} {e.text}")]
    assert any("load cell" in t for t in named), [f"{e.name} {e.text}" for e in run.record.events]
    bad = survived(run, result, *reference)
    assert not bad, bad


def test_a_heater_command_answered_by_another_module_stops_the_test(tmp_path, env):
    rule = Rule("to_host", "readdress", request=rb"^@01DO01", transform=dcon_readdress(3), limit=1, start_s=1.0)  # while loading
    run, inj, rig, _ = injected_run(tmp_path, env, {"furnace": [rule]}, *HEAT, name="readdress")
    assert rule.hits == 1, "the heater was never switched on: nothing to re-address"
    assert run.code == 3, (run.code, run.err)
    assert run.record.meta["status"] == "aborted"
    texts = [f"{e.name} {e.text}" for e in run.record.events]
    assert any("furnace" in t and "03" in t for t in texts), texts
    lines = [line for line in run.err.splitlines() if line.startswith("flowcurve: error:")]
    assert len(lines) == 1 and "furnace" in lines[0] and "03" in lines[0], run.err
    assert any("host watchdog timed out" in line and "relay off" in line for line in rig.lines)  # the heater left to it
