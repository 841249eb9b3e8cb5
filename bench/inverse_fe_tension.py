"""Inverse FE identification of tension on CalculiX necking records: solver runs, time and accuracy.

    python bench/inverse_fe_tension.py [--workers 2] [--cases voce swift jc]

Each record is a CalculiX necking run of a known law on a finer mesh (10×40) than the inverse's
model (8×30), with its own taper, 120 increments (a small first one: the elastic line resolved), noise, 1 µm
encoder steps and frame compliance
(:func:`flowcurve.identification.fe.synthetic.tension_record`). It is identified with
``--method inverse-fe``; printed: solver runs, wall time, the fitted taper against the record's,
the fracture stress against the input law's with its standard error ((σ − σ_true)/se), and the
largest flow-curve error from ε_p 0.002 to fracture of the fast (Johnson–Cook, extrapolated) and
the inverse result. The run cache is bypassed (a private temporary cache) so the times are real.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from functools import partial

import numpy as np

from flowcurve.cli.identification import solver_runs_text
from flowcurve.identification.fe.inverse_tension import identify_inverse_fe_tension
from flowcurve.identification.fe.synthetic import johnson_cook_flow, swift_flow, tension_case_model, tension_record, voce_flow
from flowcurve.identification.fe.model.tension import simulate_tension
from flowcurve.identification.laws.hardening import fit_hardening

CASES = {  # law, the record's taper
    "voce": (partial(voce_flow, s0=300.0, q=400.0, b=8.0), 0.004),
    "swift": (partial(swift_flow, K=900.0, eps0=0.01, n=0.2), 0.003),
    "jc": (partial(johnson_cook_flow, A=350.0, B=600.0, n=0.45), 0.005),
}


def curve_error(eps_p, stress_MPa, flow) -> float:
    e, s = np.asarray(eps_p, float), np.asarray(stress_MPa, float)
    return float(np.max(np.abs(s / flow(e) - 1.0)))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--cases", nargs="+", default=list(CASES), choices=list(CASES))
    a = ap.parse_args(argv)
    print("| law (record's taper) | runs | wall s | taper ± se | fracture σ ± se, MPa | true σ_f | (σ − true)/se | fast err | inverse err | force rms % | neck res mm |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for name in a.cases:
        flow, taper = CASES[name]
        record = tension_record(simulate_tension(tension_case_model(flow, taper)))
        with tempfile.TemporaryDirectory() as tmp:
            saved = os.environ.get("FLOWCURVE_FE_CACHE")
            os.environ["FLOWCURVE_FE_CACHE"] = tmp
            try:
                t0 = time.perf_counter()
                ident = identify_inverse_fe_tension(record, workers=a.workers)
                wall = time.perf_counter() - t0
            finally:
                os.environ.pop("FLOWCURVE_FE_CACHE") if saved is None else os.environ.__setitem__("FLOWCURVE_FE_CACHE", saved)
        inv, res = ident.result["inverse_fe"], ident.result
        tc = ident.true_curve
        # the fast result: its law fitted on the measured uniform range, extrapolated to fracture
        ep_u, sig_u = ident.curves["true"]["true_plastic_strain"].to_numpy(), ident.curves["true"]["true_stress_MPa"].to_numpy()
        fast_law = fit_hardening(ep_u[ep_u > 0.002], sig_u[ep_u > 0.002], res["hardening_alternatives"]["fast"].get("law") or "johnson_cook")
        grid = tc["true_plastic_strain"].to_numpy()
        eps_f = float(res["fracture_true_strain"])
        true_f = float(flow(eps_f))
        se = inv["fracture_true_stress_MPa_stderr"]
        z = (inv["fracture_true_stress_MPa"] - true_f) / se if se else float("nan")
        print(f"| {name} ({100 * taper:.1f} %) | {solver_runs_text(inv, '')} | {wall:.0f} | {100 * inv['taper']:.2f} ± {100 * inv['taper_stderr']:.2f} % | "
              f"{inv['fracture_true_stress_MPa']:.1f} ± {se:.1f} | {true_f:.1f} | {z:+.2f} | {100 * curve_error(grid, fast_law(grid), flow):.2f} % | "
              f"{100 * curve_error(grid, tc['true_stress_MPa'], flow):.2f} % | {inv['force_rms_residual_pct']:.2f} | {inv['neck_radius_residual_mm']:+.4f} |", flush=True)


if __name__ == "__main__":
    main()
