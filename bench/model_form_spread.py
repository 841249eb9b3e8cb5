"""The spread of the upsetting answer across meshes, settings and models at a given law, μ and
h0/d0: the model-form error that :mod:`identification.fe.model.model_form` turns into σ (issue 37).

    python bench/model_form_spread.py [--only C2,C3]

Per case, the product's model (identification/fe/model/upsetting.py) at its defaults (24 core
elements, stick slope 1e7, 50 increments) and at one setting changed each (30 core elements;
stick slope 1e5; 200 increments), and the second model (tests/fe/second_model.py, CAX8R graded,
node-to-surface, stick 1e5, 200 increments), all driven to the same final height. Printed
against the product's default: the bulge ΔR = (dmax − d_n)/2 (relative change), the end face's
d/d_n (absolute change), both sprung back elastically, and the force (largest relative change
over ε 0.1 to the end). One ccx at a time; the runs go to $FLOWCURVE_FE_CACHE (a new folder
makes them all run).

``--profile`` also prints the force's change at ε 0.1, 0.2, … 0.7 per variant and in quadrature
(also per unit μ).

Measured (one ccx at a time, load average 1 → 8 from other work; 6–100 s a run): the table in
docs/methods.md §4a.7 — in quadrature per case at most ΔR 4.3 % (C2), d/d_n 0.017 (C3), force
0.24 / 1.7 / 2.4 / 3.6 % at μ 0.05 / 0.15 / 0.2 / 0.3; S4 (h0/d0 2, μ 0.2) stops in the product's
model at the fold-over with every setting, S2's stick 1e5 and 200-increment runs too. Along the
stroke (``--profile``, 2026-11-29): 0.016–0.044 per unit μ up to the band before the fold-over,
0.07–0.11 within it and beyond (docs/methods.md §4a.7).
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "fe"))

import second_model as sm  # noqa: E402

from flowcurve.identification.fe.model.upsetting import UpsettingModel, simulate_upsetting  # noqa: E402

CASES = {c.name: c for c in (
    sm.Case("C1", 105.0, 1392.0, 0.642, 194_000.0, 0.15, 6.0, 9.0, 4.5),  # h0/d0 1.5, μ 0.15
    sm.C2,  # h0/d0 1.5, μ 0.05
    sm.C3,  # h0/d0 1.0, μ 0.2
    sm.Case("S4", 200.0, 700.0, 0.40, 200_000.0, 0.20, 5.0, 10.0, 5.0),  # h0/d0 2, μ 0.2
    sm.Case("S2", 250.0, 900.0, 0.50, 200_000.0, 0.30, 6.0, 7.2, 3.6),  # h0/d0 1.2, μ 0.3
)}
VARIANTS = {"product": {}, "mesh 30": {"nr": 30, "layer_fraction": 1.0 / 30.0}, "stick 1e5": {"stick_slope_MPa_per_mm": 1e5},
            "200 inc": {"increments": 200}}
FORCE_FROM_STRAIN = 0.1
PROFILE_STRAINS = (0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7)


def force_profile(ref, other, strains=PROFILE_STRAINS) -> list[float]:
    """The force's relative change at each of ``strains`` (NaN beyond either run's end)."""
    (e0, f0, _, _), (e1, f1, _, _) = ref, other
    end = min(e0.max(), e1.max())
    return [float(np.interp(e, e1, f1) / np.interp(e, e0, f0) - 1.0) if e <= end else math.nan for e in strains]


def _shape(case, stroke, force, height, dmax, dface):
    """(strain, force, ΔR mm, dface/d_n) at the end, the diameters sprung back d·(1 − ν·σ/E), σ = F/A."""
    sigma = force[-1] / (math.pi * case.d0_mm**2 * case.h0_mm / (4.0 * height))
    spring = 1.0 - case.nu * sigma / case.E_MPa
    hk = height * (1.0 + sigma / case.E_MPa)
    d_n = case.d0_mm * math.sqrt(case.h0_mm / hk)
    strain = -np.log(1.0 - np.asarray(stroke) / case.h0_mm)
    return strain, np.asarray(force), (dmax * spring - d_n) / 2.0, dface * spring / d_n


def product(case, **settings):
    m = UpsettingModel.from_law(case.d0_mm, case.h0_mm, case.h_end_mm, case.mu, case.flow, E_MPa=case.E_MPa, nu=case.nu, **settings).realising()
    t0 = time.perf_counter()
    r = simulate_upsetting(m)
    return _shape(case, r.stroke_mm, r.force_N, float(r.height_mm[-1]), float(r.dmax_mm[-1]), float(r.dtop_mm[-1])), time.perf_counter() - t0


def second(case):
    run = sm.simulate(case)
    sigma = run.force_N[-1] / (math.pi * case.d0_mm**2 * case.h0_mm / (4.0 * run.height_mm))
    spring = 1.0 - case.nu * sigma / case.E_MPa  # simulate() has sprung its diameters back: undo, _shape does it again
    return _shape(case, run.stroke_mm, run.force_N, run.height_mm, run.dmax_mm / spring, run.dface_mm / spring), run.solver_s


def compare(ref, other) -> tuple[float, float, float]:
    """(ΔR relative change, d/d_n change, largest force relative change over ε ≥ 0.1)."""
    (e0, f0, b0, face0), (e1, f1, b1, face1) = ref, other
    sel = (e0 >= FORCE_FROM_STRAIN) & (e0 <= min(e0.max(), e1.max()))
    force = np.max(np.abs(np.interp(e0[sel], e1, f1) / f0[sel] - 1.0))
    return b1 / b0 - 1.0, face1 - face0, float(force)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", default="", help="comma-separated case names")
    ap.add_argument("--profile", action="store_true", help="also the force's change along the stroke, per variant and in quadrature")
    args = ap.parse_args()
    names = [n for n in CASES if not args.only or n in args.only.split(",")]
    print("case  h0/d0  mu   | variant      | dR mm   dR change | d/d_n   change  | force change | solver s")
    for name in names:
        case = CASES[name]
        runs = {}
        for label, settings in VARIANTS.items():
            try:
                runs[label] = product(case, **settings)
            except Exception as exc:  # noqa: BLE001 — a run that stops is a row of the table
                runs[label] = (None, str(exc).splitlines()[0][:80])
        try:
            runs["second model"] = second(case)
        except RuntimeError as exc:
            runs["second model"] = (None, str(exc).splitlines()[0][:80])
        ref = runs["product"][0]
        for label, (shape, info) in runs.items():
            head = f"{name:4s} {case.h0_mm / case.d0_mm:5.2f} {case.mu:5.2f} | {label:12s} |"
            if shape is None or ref is None:
                print(f"{head} did not finish: {info if shape is None else 'the product did not'}")
                continue
            db, dface, df = compare(ref, shape)
            print(f"{head} {shape[2]:6.4f} {100 * db:+7.1f} % | {shape[3]:6.4f} {dface:+7.4f} | {100 * df:8.2f} %   | {info:6.1f}", flush=True)
        if args.profile and ref is not None:
            rows = {label: force_profile(ref, shape) for label, (shape, _) in runs.items() if shape is not None and label != "product"}
            print(f"{name}: force change % at ε " + " ".join(f"{e:6.2f}" for e in PROFILE_STRAINS))
            for label, row in rows.items():
                print(f"  {label:12s}" + " ".join(f"{100 * v:+6.2f}" for v in row))
            squares = np.square(list(rows.values()))
            total = np.where(np.all(np.isnan(squares), axis=0), np.nan, np.sqrt(np.nansum(squares, axis=0)))  # a run that stopped: left out
            print(f"  {'quadrature':12s}" + " ".join(f"{100 * v:6.2f}" for v in total) + f"   per μ: " + " ".join(f"{v / case.mu:5.3f}" for v in total), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
