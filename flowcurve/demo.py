"""``flowcurve demo``: a virtual tension and a virtual compression test, recorded and identified.

Both tests run on the virtual rig through the real drivers over pseudo-terminals, are
written as flowcurve records, identified (``identification.identify``) and plotted
(``reports.plots``); the identified hardening is compared with the virtual material's
Johnson–Cook curve at the test's rate and temperature — the truth the rig was built from.

The virtual compression test makes its force and barrel from CalculiX upsetting runs, not
from the slab factor and the seed's regression (3.18) the identification's methods invert, so
the demo prints, for every friction method and every correction, the μ it reads and the error
of the corrected flow curve against the virtual material (:func:`friction_comparison`). The
identification's ``fe_table`` method reads the same CalculiX runs (interpolated and with a
hardening exponent of its own): it is the reference, not an independent check.

Likewise the virtual tension test's neck comes from CalculiX necking runs, not from the
Bridgman factor and Le Roy's a/R the identification's neck corrections use, so the demo prints
each neck correction's fracture stress — with the neck radius the rig reports and with Le Roy's
estimate — and the identified curve past necking against the virtual material
(:func:`neck_comparison`). ``tension_response="bridgman"`` / ``compression_response="slab"``
run the analytic mirrors instead (the errors then show what the identification adds itself).
"""

from __future__ import annotations

import math
import time
from pathlib import Path

import numpy as np

from flowcurve.acquisition.live import LiveView
from flowcurve.acquisition.procedure import TestSpec
from flowcurve.record.format import read_record
from flowcurve.acquisition.session import run_virtual_test
from flowcurve.errors import EXIT_DATA_LOST, IdentificationError
from flowcurve.identification.laws.hardening import johnson_cook_static

DEMO_TIME_SCALE = 15.0  # at DEMO_SPEED_MM_PER_S; the virtual load cell sends 100 values per wall second: enough
DEMO_SPEED_MM_PER_S = 0.05  # compression: samples on the elastic line at 0.75 mm of crosshead per wall second
# tension: ISO 6892-1 method A range 2, ė_Lc = v/Lc = 0.00025 1/s on the 30 mm specimen, in every phase (A222);
# 0.05 mm/s (0.0017 1/s) was in no method A range and 140 MPa/s on the elastic line, above method B's 60 MPa/s
DEMO_TENSION_SPEED_MM_PER_S = 0.0075
ERROR_STRAIN_RANGE = (0.05, 0.6)  # plastic strains of the flow-curve error (up to the strain reached)


def curve_error_pct(curve, material, strain_rate_per_s: float, temperature_C: float, strain_range=ERROR_STRAIN_RANGE) -> float:
    """Max |σ/σ_true − 1| in % of a corrected true curve (``true_plastic_strain``,
    ``true_stress_MPa``) over the plastic strains ``strain_range``; NaN if none lie there."""
    eps = np.asarray(curve["true_plastic_strain"], dtype=float)
    stress_MPa = np.asarray(curve["true_stress_MPa"], dtype=float)
    inside = (eps >= strain_range[0]) & (eps <= strain_range[1]) & np.isfinite(stress_MPa)
    if not inside.any():
        return math.nan
    truth = material.flow_stress(eps[inside], strain_rate_per_s, temperature_C)
    return float(100.0 * np.max(np.abs(stress_MPa[inside] / truth - 1.0)))


def friction_comparison(record, run, default=None) -> dict:
    """Every friction method × every correction on one compression record, against the truth.

    Returns ``{"strain_range": (lo, hi), "corrections": [...], "rows": [{"method", "mu",
    "error_pct": {correction: %}} ...]}``; ``default`` is an identification of ``record`` with
    the default friction method, reused rather than computed again.
    """
    from flowcurve.identification.compression import friction as fr
    from flowcurve.identification.identify import identify

    rows, reached = [], math.inf
    for method in fr.FRICTION_METHODS:
        try:
            ident = default if (default is not None and method == fr.DEFAULT_FRICTION_METHOD) else identify(record, friction_method=method)
        except IdentificationError as exc:
            rows.append({"method": method, "mu": None, "error_pct": {}, "error": str(exc)})
            continue
        reached = min(reached, float(np.nanmax(ident.curves[f"true_{fr.DEFAULT_CORRECTION}"]["true_plastic_strain"])))
        rows.append({"method": method, "mu": ident.result["friction_mu"], "ident": ident})
    lo, hi = ERROR_STRAIN_RANGE[0], min(ERROR_STRAIN_RANGE[1], reached)
    for row in rows:
        ident = row.pop("ident", None)
        if ident is not None:
            row["error_pct"] = {c: curve_error_pct(ident.curves[f"true_{c}"], run.material, run.strain_rate_per_s,
                                                   run.temperature_C, (lo, hi)) for c in fr.CORRECTIONS}
    return {"strain_range": (lo, hi), "corrections": list(fr.CORRECTIONS), "rows": rows}


def friction_comparison_lines(table: dict, run) -> list[str]:
    """The demo's friction table: μ read and flow-curve error per method and correction."""
    lo, hi = table["strain_range"]
    cols = table["corrections"]
    lines = [f"  friction, every method and correction: μ read (virtual μ {run.friction_mu:g}, rig response "
             f"{getattr(run, 'compression_response', 'fe')}) and max |σ/σ_true − 1| of the corrected curve over εp {lo:.2f}…{hi:.2f}",
             "    " + f"{'friction method':22s} {'μ':>6s}  " + "  ".join(f"{c:>9s}" for c in cols)]
    for row in table["rows"]:
        if row["mu"] is None:
            lines.append(f"    {row['method']:22s} not applicable: {row['error']}")
            continue
        errs = "  ".join(f"{row['error_pct'][c]:8.1f}%" for c in cols)
        lines.append(f"    {row['method']:22s} {row['mu']:6.3f}  {errs}")
    return lines


def neck_comparison(record, ident, run) -> dict:
    """Every neck correction of one tension identification, with the measured neck radius and
    with Le Roy's a/R, against the virtual material's flow stress at the fracture strain; and
    the identified hardening law's deviation from the truth between the maximum force and fracture.

    Returns ``{"eps_u", "eps_f", "truth_MPa", "methods", "rows": [{"source", "a_over_R",
    "error_pct": {method: %}}], "curve_error_pct", "curve_range"}`` (empty without a fracture point).
    """
    from flowcurve.identification.tension.necking import METHODS, neck_corrections

    res = ident.result
    eps_f, avg = res.get("fracture_true_strain"), res.get("fracture_avg_stress_MPa")
    if eps_f is None or avg is None:
        return {}
    eps_u = float(res["uniform_true_strain"])
    truth = float(run.material.flow_stress(eps_f, run.strain_rate_per_s, run.temperature_C))
    dk = record.specimen.dk_mm
    variants = [("reported", res["neck_corrections"])]
    if record.specimen.neck_radius_mm is not None:  # the same without the radius: Le Roy's a/R
        variants.append(("Le Roy", neck_corrections(avg, eps_f, eps_u, d_k_mm=dk)))
    rows = [{"source": corr["a_over_R_source"] if name == "reported" else corr["a_over_R_source"].split(":")[0],
             "a_over_R": corr["a_over_R"], "error_pct": {m: 100.0 * (corr[m]["stress_MPa"] / truth - 1.0) for m in METHODS}}
            for name, corr in variants]
    hard = res["hardening"]
    lo = float(res["uniform_true_plastic_strain"])
    curve = (hardening_deviation_pct(hard, run.material, run.strain_rate_per_s, run.temperature_C, (lo, eps_f))
             if {"A_MPa", "B_MPa", "n"} <= set(hard) and eps_f > lo else math.nan)
    return {"eps_u": eps_u, "eps_f": float(eps_f), "truth_MPa": truth, "avg_MPa": float(avg), "methods": list(METHODS),
            "rows": rows, "curve_error_pct": curve, "curve_range": (lo, float(eps_f)), "law": hard.get("law", "")}


def neck_comparison_lines(table: dict, run) -> list[str]:
    """The demo's neck table: error of every neck correction at fracture, per a/R source."""
    if not table:
        return ["  neck corrections: no fracture point (no post.dk_mm), nothing to compare"]
    cols = table["methods"]
    lines = [f"  neck corrections at fracture (rig tension response {getattr(run, 'tension_response', 'fe')}): ε_f {table['eps_f']:.3f}, "
             f"P_k/F_k {table['avg_MPa']:.0f} MPa, virtual σ_f(ε_f) {table['truth_MPa']:.0f} MPa; σ/σ_true − 1 of each correction",
             "    " + f"{'a/R from':34s} {'a/R':>6s}  " + "  ".join(f"{c:>10s}" for c in cols)]
    for row in table["rows"]:
        errs = "  ".join(f"{row['error_pct'][c]:+9.1f}%" for c in cols)
        lines.append(f"    {row['source'][:34]:34s} {row['a_over_R']:6.3f}  {errs}")
    lo, hi = table["curve_range"]
    if math.isfinite(table["curve_error_pct"]):
        lines.append(f"  identified curve ({table['law']}) past necking: max |σ/σ_true − 1| over εp {lo:.3f}…{hi:.3f}: {table['curve_error_pct']:.1f} %")
    return lines


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


def demo_time_scale(spec: TestSpec, time_scale: float = DEMO_TIME_SCALE) -> float:
    """The time scale that runs ``spec`` at the same crosshead travel per wall second as the
    compression demo at ``time_scale`` (so the same samples per mm of crosshead and the same wall time)."""
    return time_scale * DEMO_SPEED_MM_PER_S / spec.speed_mm_per_s


def demo_specs(material_name: str) -> list[TestSpec]:
    """The demo's tension and compression specs for ``material_name``."""
    from flowcurve.rig.virtual.physics import Specimen

    t, c = Specimen.tension(), Specimen.compression()
    return [
        TestSpec("tension", material=material_name, operator="demo", specimen_id="demo-T1", geometry_mm={"d0_mm": t.d0_mm, "l0_mm": t.length0_mm}, speed_mm_per_s=DEMO_TENSION_SPEED_MM_PER_S),
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
    return lines


def run_demo(out: Path, *, material: str = "steel45", quiet: bool = False, time_scale: float = DEMO_TIME_SCALE,
             compression_response: str = "fe", tension_response: str = "fe", faults: tuple = ()) -> int:
    """Run the demo series on the virtual rig into ``out``, identify and fit it; the exit status."""
    out = Path(out)
    view = LiveView(quiet=quiet)
    t_start = time.monotonic()
    print(f"flowcurve demo — virtual rig ({material}; tension response {tension_response}, compression response "
          f"{compression_response}), real drivers over pseudo-terminals, time scale {time_scale:g}")
    losses = []
    for spec in demo_specs(material):
        record_path = out / "records" / f"{spec.test}.csv"
        t0 = time.monotonic()
        run = run_virtual_test(spec, record_path, material=material, time_scale=demo_time_scale(spec, time_scale), view=view, faults=faults,
                               compression_response=compression_response, tension_response=tension_response)
        o = run.outcome
        print(f"\n{spec.test}: recorded {o.samples} samples ({o.duration_s:.0f} s of test in {time.monotonic() - t0:.1f} s) → {o.path}; {o.reason}")
        if o.status != "complete":
            print(f"  the test did not complete ({o.reason}); not identified")
            return o.error.exit_code if o.error is not None else 1
        if o.losses:
            print(f"  data lost or rejected: {o.losses} (declared in the record's events)")
            losses.append(o.losses)
        ident, folder = identify_and_write(o.path, out / "results")
        print("\n".join(summary_lines(run, ident, folder)))
        if spec.test == "compression":
            print("\n".join(friction_comparison_lines(friction_comparison(read_record(o.path), run, default=ident), run)))
        else:
            print("\n".join(neck_comparison_lines(neck_comparison(read_record(o.path), ident, run), run)))
    print(f"\ndone in {time.monotonic() - t_start:.1f} s. Next: flowcurve identify {out / 'records' / 'tension.csv'} --out results/; "
          f"'flowcurve run tension --help' for a test of your own.")
    return EXIT_DATA_LOST if losses else 0
