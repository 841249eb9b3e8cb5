"""Stored heat after a working heater switch-off: how far above the set-point the furnace goes.

Runs heated tests on the virtual rig in this process on model time (the real drivers over
``virtual://`` ports, :class:`flowcurve.clock.ModelClock`) with the furnace's maximum out of the
way (1370 C), and logs every reading the furnace driver takes with the heater's commanded state
and the model's true furnace temperature. For each run it prints the highest temperature after
the last reading with the heater commanded on, as a rise above the set-point (the margin a
set-point must leave below the maximum) and above the temperature at the switch-off.

Switch-offs (``--cases``):

Every run heats from 20 C at the configured rate (30 C/min), soaks ``--soak`` s and loads; the
highest temperature with the heater on (the approach's own overshoot) is printed too.

* ``end``: the test runs to its end;
* ``fault``: the load cell falls silent 1 mm into the loading (a device fault stops the test);
* ``ctrlc-load``: Ctrl-C 1 mm into the loading (an operator stop);
* ``ctrlc-heat``: Ctrl-C while heating, at the first reading within ``gap`` C of the set-point
  (the approach, the heater at its highest duty near the set-point), for each gap.

The model's worst case is printed beside: the heater at full power through the dead time,
``dead_time · (P − losses(T))/C`` at the set-point (the relay's last dead-time of switching acts
after the switch-off).

Usage: python bench/stored_heat.py [--setpoints 100,300,500,700,850,890,895] [--cases end,fault,...]
       [--tests tension,compression] [--speeds 0.05,0.5] [--time-scale 1] [--gaps 20,5,1] [--rate 200]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

MAX_OUT_OF_THE_WAY_C = 1370.0  # the configuration's highest maximum: no alarm interferes with the measurement
AMBIENT_C = 20.0


def full_power_rise_C(setpoint_C: float) -> float:
    """The virtual furnace's worst case: full power through the dead time at the set-point, C."""
    from flowcurve.rig.virtual.physics import FurnaceParams

    p = FurnaceParams()
    theta = setpoint_C - p.ambient_C
    return p.dead_time_s * (p.heater_power_W - (p.loss_W_per_K + p.loss_W_per_K2 * theta) * theta) / p.heat_capacity_J_per_K


def run_case(setpoint_C: float, case: str, test: str, speed: float, time_scale: float, gap_C: float | None, soak_s: float,
             workdir: Path, rate_C_per_min: float | None = None) -> dict:
    """One heated test; the readings' summary around the last switch-off."""
    from flowcurve.acquisition.procedure import TestSpec
    from flowcurve.acquisition.stopping import StopCriteria
    from flowcurve.acquisition.safety import Interrupted
    from flowcurve.acquisition.session import run_virtual_test
    from flowcurve.clock import ModelClock
    from flowcurve.rig.furnace import Furnace

    geometry = {"d0_mm": 6.0, "l0_mm": 30.0} if test == "tension" else {"d0_mm": 5.989, "h0_mm": 6.982}
    spec = TestSpec(test, material="steel45", geometry_mm=geometry, temperature_C=setpoint_C, speed_mm_per_s=speed,
                    soak_s=soak_s, stop=StopCriteria(target_displacement_mm=3.0 if test == "compression" else None))
    rigs, readings = [], []  # readings: (model s, reading C, heater commanded on, true C)
    real_read = Furnace.temperature_C

    def logged(furnace):
        value = real_read(furnace)
        vr = rigs[0]
        readings.append((vr.now(), value, furnace.heater_is_on, vr.model.furnace.temperature_C))
        return value

    loading_from, injected = [], []  # model time the crosshead started; the fault once injected

    def setup(vr):
        rigs.append(vr)
        start = vr.start_crosshead

        def started():
            loading_from.append(vr.now())
            start()

        vr.start_crosshead = started

    def stop_requested():
        if not rigs or not readings:
            return None
        vr = rigs[0]
        if case == "ctrlc-heat" and abs(readings[-1][1] - setpoint_C) <= gap_C:
            raise Interrupted("SIGINT")
        if loading_from and vr.now() - loading_from[0] >= 1.0 / speed:
            if case == "ctrlc-load":
                raise Interrupted("SIGINT")
            if case == "fault" and not injected:
                injected.append(vr.now())
                vr.inject("loadcell", "silence")
        return None

    Furnace.temperature_C = logged
    t0 = time.monotonic()
    try:
        run = run_virtual_test(spec, workdir / f"{test}-{setpoint_C:g}-{case}-{gap_C}.csv", material="steel45",
                               time_scale=time_scale, clock=ModelClock(), link="inprocess", rig_setup=setup,
                               initial_temperature_C=AMBIENT_C,
                               config_overrides={"furnace_max_temperature_C": MAX_OUT_OF_THE_WAY_C,
                                                 **({"furnace_max_heating_rate_C_per_min": rate_C_per_min} if rate_C_per_min else {})},
                               stop_requested=stop_requested)
    finally:
        Furnace.temperature_C = real_read
    last_on = max((i for i, r in enumerate(readings) if r[2]), default=None)
    if last_on is None:
        return {"error": "the heater was never on"}
    on, off = readings[:last_on + 1], readings[last_on + 1:]
    t_off, at_off_C = off[0][0], off[0][3]
    peak = max(off, key=lambda r: r[1])
    peak_true = max(off, key=lambda r: r[3])
    return {"status": run.outcome.status, "reason": run.outcome.reason[:60], "wall_s": time.monotonic() - t0,
            "at_off_C": at_off_C - setpoint_C, "peak_reading_C": peak[1] - setpoint_C, "peak_true_C": peak_true[3] - setpoint_C,
            "rise_C": peak_true[3] - at_off_C, "peak_after_s": peak_true[0] - t_off,
            "on_peak_C": max(r[3] for r in on) - setpoint_C}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--setpoints", default="100,300,500,700,850,890,895")
    ap.add_argument("--cases", default="end,fault,ctrlc-load,ctrlc-heat")
    ap.add_argument("--tests", default="tension,compression")
    ap.add_argument("--speeds", default="0.05,0.5")
    ap.add_argument("--time-scale", type=float, default=1.0, help="model s per host s (default 1: the controller steps as on the rig; the matrix's heated cells run at up to 50)")
    ap.add_argument("--soak", type=float, default=60.0, help="soak at the set-point, s (run's default 60)")
    ap.add_argument("--rate", type=float, default=None, help="[furnace] max_heating_rate_C_per_min (default: the configuration's 30)")
    ap.add_argument("--gaps", default="20,5,1", help="ctrlc-heat: Ctrl-C at the first reading this close to the set-point, C")
    a = ap.parse_args()
    setpoints = [float(s) for s in a.setpoints.split(",")]
    cases, tests = a.cases.split(","), a.tests.split(",")
    speeds = [float(s) for s in a.speeds.split(",")]
    gaps = [float(g) for g in a.gaps.split(",")]
    print(f"time scale {a.time_scale:g}, soak {a.soak:g} s, heating rate {a.rate or 30:g} C/min; rises in C above the set-point; 'rise' is above the true temperature at the switch-off")
    print(f"{'set C':>6} {'case':<10} {'test':<11} {'mm/s':>5} {'gap':>4} | {'at off':>6} {'peak rd':>7} {'peak':>6} {'rise':>5} "
          f"{'after s':>7} {'on pk':>6} | {'full-P':>6} | {'status':<9} wall s")
    worst = {}
    with tempfile.TemporaryDirectory() as tmp:
        for s in setpoints:
            for case in cases:
                for test in tests:
                    for speed in (speeds if case != "ctrlc-heat" else speeds[:1]):
                        for gap in (gaps if case == "ctrlc-heat" else [None]):
                            r = run_case(s, case, test, speed, a.time_scale, gap, a.soak, Path(tmp), a.rate)
                            if "error" in r:
                                print(f"{s:6g} {case:<10} {test:<11} {speed:5g}: {r['error']}")
                                continue
                            worst[s] = max(worst.get(s, -1e9), r["peak_reading_C"], r["on_peak_C"])
                            print(f"{s:6g} {case:<10} {test:<11} {speed:5g} {'' if gap is None else f'{gap:g}':>4} | "
                                  f"{r['at_off_C']:+6.2f} {r['peak_reading_C']:+7.2f} {r['peak_true_C']:+6.2f} {r['rise_C']:5.2f} "
                                  f"{r['peak_after_s']:7.1f} {r['on_peak_C']:+6.2f} | {full_power_rise_C(s):6.2f} | "
                                  f"{r['status']:<9} {r['wall_s']:.1f}" + ("" if r["status"] == "complete" else f" ({r['reason']})"), flush=True)
    print("highest reading above the set-point, heater on or after the switch-off, per set-point:")
    for s, w in worst.items():
        print(f"  {s:6g} C: {w:+.2f} C (full power through the dead time: {full_power_rise_C(s):.2f} C)")


if __name__ == "__main__":
    main()
