"""Inverse FE identification on CalculiX upsetting records: solver runs, time and accuracy.

    python bench/inverse_fe.py [--workers 2] [--cases 0 2] [--law auto] [--face]

Each record (:data:`flowcurve.identification.fe.synthetic.VALIDATION_CASES`, with toe, noise
and frame compliance) is identified with ``--method inverse-fe`` (the hardening law that best
fits the fast curve, and μ, CalculiX in the loop, warm start from the fast fe_table method);
printed: the law, solver runs, wall time, μ read vs true, and the largest flow-curve error over
ε_p 0.05–0.6 of the fast and the inverse result. The run cache is bypassed (a private temporary
cache) so the times are real.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time

import numpy as np

from flowcurve.cli.identification import solver_runs_text
from flowcurve.identification.compression.identify import identify_compression
from flowcurve.identification.identify import identify_inverse_fe
from flowcurve.identification.fe.synthetic import VALIDATION_CASES, case_flow, run_case, upsetting_record


def curve_error(true_curve, flow) -> float:
    e, s = true_curve["true_plastic_strain"].to_numpy(), true_curve["true_stress_MPa"].to_numpy()
    sel = (e >= 0.05) & (e <= 0.6)
    return float(np.max(np.abs(s[sel] / flow(e[sel]) - 1.0)))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--cases", type=int, nargs="+", default=list(range(len(VALIDATION_CASES))))
    ap.add_argument("--law", default="auto", help="hardening law of the inverse (default: the best fit to the fast curve)")
    ap.add_argument("--face", action="store_true", help="the records carry the original end face's diameter (post.dface_mm)")
    a = ap.parse_args(argv)
    print("| FE record | true μ | fast μ | law | inverse μ ± se | se, dmax alone | ρ force | fast err | inverse err | runs | wall s | force rms % |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for k in a.cases:
        case = VALIDATION_CASES[k]
        rec = upsetting_record(run_case(case), seed=5, specimen_id=case["name"], end_face=a.face)
        with tempfile.TemporaryDirectory() as tmp:
            os.environ["FLOWCURVE_FE_CACHE"] = tmp
            t0 = time.perf_counter()
            inv = identify_inverse_fe(rec, law=a.law, workers=a.workers)
            wall = time.perf_counter() - t0
        fast = identify_compression(rec)
        flow = case_flow(case)
        r = inv.result["inverse_fe"]
        print(f"| {case['name']} | {case['mu']:.2f} | {fast.result['friction_mu']:.3f} | {inv.result['hardening']['law']} | {r['mu']:.4f} ± {r['mu_stderr']:.4f} | "
              f"{r['mu_stderr_shape_alone'] or float('nan'):.4f} | {r['force_residual_serial_correlation']:.2f} | "
              f"{100 * curve_error(fast.true_curve, flow):.2f} % | {100 * curve_error(inv.true_curve, flow):.2f} % | {solver_runs_text(r, '')} | {wall:.0f} | {r['force_rms_residual_pct']:.3f} |", flush=True)


if __name__ == "__main__":
    main()
