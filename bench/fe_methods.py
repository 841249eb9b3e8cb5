"""Friction methods × CalculiX upsetting records: μ read and flow-curve error.

    python bench/fe_methods.py [--workers 2]

The records are CalculiX upsetting runs the FE table did not train on
(:data:`flowcurve.identification.fe.synthetic.VALIDATION_CASES`: other μ, h0/d0, d0 and
hardening laws), with a seating toe, 10 µm encoder steps, force noise and the frame
compliance. Each is identified with every friction method; every correction is applied with
the default (fe_table) μ, and the seed's pair (3.19) + K_σ/K_ε with its own μ. The error is
the largest |σ/σ_true − 1| of the corrected curve over ε_p 0.05–0.6. The last two columns: the
default again with the original end face measured (post.dface_mm, the record's rim node).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from flowcurve.errors import IdentificationError
from flowcurve.identification.compression.identify import identify_compression
from flowcurve.identification.fe.pool import run_many
from flowcurve.identification.fe.synthetic import VALIDATION_CASES, case_flow, run_case, upsetting_record

RANGE = (0.05, 0.6)


def curve_error(ident, correction: str, flow) -> float:
    c = ident.curves[f"true_{correction}"]
    e, s = c["true_plastic_strain"].to_numpy(), c["true_stress_MPa"].to_numpy()
    sel = (e >= RANGE[0]) & (e <= RANGE[1])
    return float(np.max(np.abs(s[sel] / flow(e[sel]) - 1.0)))


def evaluate(case, run, seed=1):
    rec = upsetting_record(run, seed=seed, specimen_id=case["name"])
    flow = case_flow(case)
    default = identify_compression(rec)
    try:
        seed_pair = curve_error(identify_compression(rec, friction_method="bulge_regression", friction_correction="k_sigma"), "k_sigma", flow)
    except IdentificationError as exc:  # (3.19) cannot read a bulge beyond its saturation
        seed_pair = None
        print(f"  {case['name']}: (3.19) fails: {exc}")
    with_face = identify_compression(upsetting_record(run, seed=seed, specimen_id=case["name"], end_face=True))
    row = {"name": case["name"], "mu_true": case["mu"], "mu": dict(default.result["friction"]),
           "mu_face": with_face.result["friction_mu"], "error_face": curve_error(with_face, "fe_table", flow),
           "error": {k: curve_error(default, k, flow) for k in ("fe_table", "k_sigma", "siebel", "slab")},
           "seed_pair_error": seed_pair, "n_read": default.result["friction_details"]["fe_table"].get("hardening_n")}
    return row


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--workers", type=int, default=2)
    a = ap.parse_args(argv)
    t0 = time.perf_counter()
    runs = run_many(run_case, VALIDATION_CASES, workers=a.workers)
    print(f"{len(runs)} CalculiX records: {time.perf_counter() - t0:.0f} s wall, run times {', '.join(f'{r.wall_s:.0f}' for r in runs)} s (cached: {sum(r.cached for r in runs)})")
    rows = [evaluate(c, r) for c, r in zip(VALIDATION_CASES, runs)]
    worst_mu = max(abs(r["mu"]["fe_table"] - r["mu_true"]) for r in rows)
    worst = max(r["error"]["fe_table"] for r in rows)
    worst_mu_face = max(abs(r["mu_face"] - r["mu_true"]) for r in rows)
    worst_face = max(r["error_face"] for r in rows)
    print("\n| FE record | true μ | μ fe_table | μ (3.19) | μ E–N | n read | err fe_table | err K_σ (fe μ) | err Siebel (fe μ) | err slab (fe μ) | err (3.19)+K_σ | μ fe_table, end face | err fe_table, end face |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        mu = r["mu"]
        fmt = lambda v: "—" if v is None else f"{v:.3f}"  # noqa: E731
        print(f"| {r['name']} | {r['mu_true']:.2f} | {fmt(mu.get('fe_table'))} | {fmt(mu.get('bulge_regression'))} | {fmt(mu.get('ebrahimi_najafizadeh'))} | {r['n_read']:.2f} | "
              + " | ".join(f"{100 * r['error'][k]:.1f} %" for k in ("fe_table", "k_sigma", "siebel", "slab")) + (" | fails |" if r["seed_pair_error"] is None else f" | {100 * r['seed_pair_error']:.1f} % |")
              + f" {r['mu_face']:.3f} | {100 * r['error_face']:.1f} % |")
    print(f"\ndefault (fe_table): worst μ error {worst_mu:.3f}, worst flow-curve error {100 * worst:.1f} % over ε_p {RANGE[0]}–{RANGE[1]}")
    print(f"default with the end face: worst μ error {worst_mu_face:.3f}, worst flow-curve error {100 * worst_face:.1f} %")
    return rows


if __name__ == "__main__":
    main()
