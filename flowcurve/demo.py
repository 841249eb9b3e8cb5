"""``flowcurve demo``: a virtual tension and a virtual compression test, recorded and identified.

Both tests run on the virtual rig through the real drivers over pseudo-terminals, are
written as flowcurve records, identified (``identification.identify``) and plotted
(``reports.plots``); the identified hardening is compared with the virtual material's
Johnson–Cook curve at the test's rate and temperature — the truth the rig was built from.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from flowcurve.acquisition.live import LiveView
from flowcurve.acquisition.procedure import TestSpec
from flowcurve.record.format import read_record
from flowcurve.acquisition.session import run_virtual_test
from flowcurve.identification.hardening import johnson_cook_static

DEMO_TIME_SCALE = 15.0  # the virtual load cell sends 100 values per wall second: enough
DEMO_SPEED_MM_PER_S = 0.05  # samples on the elastic line at 0.75 mm of crosshead per wall second


def hardening_deviation_pct(fit: dict, material, strain_rate_per_s: float, temperature_C: float, strain_range) -> float:
    """Max |fitted / true − 1| in % of a JC fit (A_MPa, B_MPa, n) over ``strain_range``."""
    lo, hi = (float(v) for v in strain_range)
    eps = np.linspace(max(lo, 1e-4), hi, 200)
    fitted = johnson_cook_static(eps, fit["A_MPa"], fit["B_MPa"], fit["n"])
    truth = material.flow_stress(eps, strain_rate_per_s, temperature_C)
    return float(100.0 * np.max(np.abs(fitted / truth - 1.0)))


def true_constants(material, strain_rate_per_s: float, temperature_C: float) -> dict[str, float]:
    """The virtual material's static JC constants at the test's rate and temperature."""
    factor = float(material.rate_temperature_factor(strain_rate_per_s, temperature_C))
    return {"A_MPa": material.A_MPa * factor, "B_MPa": material.B_MPa * factor, "n": material.n}


def demo_specs(material_name: str) -> list[TestSpec]:
    from flowcurve.rig.virtual.physics import Specimen

    t, c = Specimen.tension(), Specimen.compression()
    return [
        TestSpec("tension", material=material_name, operator="demo", specimen_id="demo-T1", geometry_mm={"d0_mm": t.d0_mm, "l0_mm": t.length0_mm}, speed_mm_per_s=DEMO_SPEED_MM_PER_S),
        TestSpec("compression", material=material_name, operator="demo", specimen_id="demo-C1", geometry_mm={"d0_mm": c.d0_mm, "h0_mm": c.length0_mm}, speed_mm_per_s=DEMO_SPEED_MM_PER_S),
    ]


def identify_and_write(record_path: Path, outdir: Path):
    """Identify a record, add its plots, write its result folder; (identification, folder)."""
    from flowcurve.identification.identify import identify
    from flowcurve.reports.plots import add_plots

    ident = identify(read_record(record_path))
    add_plots(ident)
    return ident, ident.write(outdir / Path(record_path).stem)


def summary_lines(run, ident, folder: Path) -> list[str]:
    """What the demo prints about one identified virtual test, against the truth."""
    res = ident.result
    truth = true_constants(run.material, run.strain_rate_per_s, run.temperature_C)
    hard = res["hardening"]
    lo, hi = hard["strain_range"]
    lines = [
        f"  results → {folder}/ (result.json, true_curve.csv, {', '.join(sorted(ident.plots))} plots)",
        f"  strain rate {run.strain_rate_per_s:.2e} /s, {run.temperature_C:.0f} C; virtual material's static JC there: "
        f"A {truth['A_MPa']:.1f} MPa, B {truth['B_MPa']:.1f} MPa, n {truth['n']:.3f}",
        f"  identified ({hard['law']}, {hard.get('correction', hard['method'])}): A {hard['A_MPa']:.1f} MPa, B {hard['B_MPa']:.1f} MPa, "
        f"n {hard['n']:.3f}; max deviation from the true curve over εp {lo:.3f}…{hi:.3f}: "
        f"{hardening_deviation_pct(hard, run.material, run.strain_rate_per_s, run.temperature_C, (lo, hi)):.1f} %",
    ]
    for warning in res.get("warnings") or []:
        lines.append(f"  warning: {warning}")
    if res.get("test") == "tension":
        lines.append(f"  E {res['E_MPa'] / 1000:.0f} GPa (apparent; true {run.material.E_MPa / 1000:.0f}), Rp0.2 {res['Rp02_MPa']:.0f} MPa, "
                     f"Rm {res['Rm_MPa']:.0f} MPa, A {res['A_pct']:.1f} %, Z {res['Z_pct']:.1f} %, fracture true strain {res['fracture_true_strain']:.3f}")
    else:
        lines.append(f"  friction μ {res['friction_mu']:.3f} ({res.get('friction_method', '')}; true {run.friction_mu:g})")
        for name, fit in (res.get("hardening_by_correction") or {}).items():
            if isinstance(fit, dict) and "A_MPa" in fit:
                dev = hardening_deviation_pct(fit, run.material, run.strain_rate_per_s, run.temperature_C, fit["strain_range"])
                lines.append(f"    correction {name:8s}: A {fit['A_MPa']:.1f}, B {fit['B_MPa']:.1f}, n {fit['n']:.3f}; "
                             f"max deviation {dev:.1f} % over εp up to {fit['strain_range'][1]:.2f}")
    return lines


def run_demo(out: Path, *, material: str = "steel45", quiet: bool = False, time_scale: float = DEMO_TIME_SCALE) -> int:
    out = Path(out)
    view = LiveView(quiet=quiet)
    t_start = time.monotonic()
    print(f"flowcurve demo — virtual rig ({material}), real drivers over pseudo-terminals, time scale {time_scale:g}")
    for spec in demo_specs(material):
        record_path = out / "records" / f"{spec.test}.csv"
        t0 = time.monotonic()
        run = run_virtual_test(spec, record_path, material=material, time_scale=time_scale, view=view)
        o = run.outcome
        print(f"\n{spec.test}: recorded {o.samples} samples ({o.duration_s:.0f} s of test in {time.monotonic() - t0:.1f} s) → {o.path}; {o.reason}")
        if o.status != "complete":
            print(f"  the test did not complete ({o.reason}); not identified")
            return 1
        ident, folder = identify_and_write(o.path, out / "results")
        print("\n".join(summary_lines(run, ident, folder)))
    print(f"\ndone in {time.monotonic() - t_start:.1f} s. Next: flowcurve identify {out / 'records' / 'tension.csv'} --out results/; "
          f"'flowcurve run tension --help' for a test of your own.")
    return 0
