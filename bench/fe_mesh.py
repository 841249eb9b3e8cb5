"""Mesh convergence of the CalculiX upsetting model: why the table and the inverse use 24 core
elements and a d0/24 rim layer.

    python bench/fe_mesh.py [--workers 2]

One Swift law σ = K·(0.1 + ε_p)^0.2, d0 = h0 = 6 mm compressed to ε = 0.9, at μ 0.1 and 0.25,
on meshes from the first default (12 core elements, a 2-element rim layer of d0/12) to 36
elements; printed: the mean pressure over K/1000 at ε = 0.7 and the bulge ΔR/h at ε = 0.3 and
0.7, each as a ratio to the finest mesh that completed in the same run, and the change of the
bulge when the stress level (σ/E) is 1.5× lower (K 675 against 1000) — a rigid-plastic barrel
does not depend on it, so what moves is the mesh's. Runs are cached (~/.cache/flowcurve/fe).
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

MESHES = {"12 / d0/12 (first default)": (12, 2, 1 / 12), "18 / d0/12": (18, 3, 1 / 12), "24 / d0/12": (24, 4, 1 / 12),
          "24 / d0/24 (default)": (24, 2, 1 / 24), "36 / d0/24": (36, 4, 1 / 24)}


def run(args):
    from flowcurve.identification.fe.model.upsetting import UpsettingModel, simulate_upsetting

    mu, (nr, layers, fraction), K = args
    flow = lambda e: K * np.power(0.1 + np.clip(e, 0.0, None), 0.2)  # noqa: E731
    m = UpsettingModel.from_law(6.0, 6.0, 6.0 * math.exp(-0.9), mu, flow, increments=60, nr=nr, layers=layers, layer_fraction=fraction)
    r = simulate_upsetting(m, require_complete=False)
    h = r.height_mm
    eps = np.log(6.0 / h)
    bulge = (r.dmax_mm - 6.0 * np.sqrt(6.0 / h)) / (2.0 * h)  # (3.29)
    p = r.force_N / (math.pi * 9.0 * 6.0 / h) / (K / 1000.0)  # (3.30) A = π·d0²·h0/(4h)
    done = float(eps[-1]) >= 0.7
    return {"p": float(np.interp(0.7, eps, p)) if done else math.nan, "b3": float(np.interp(0.3, eps, bulge)),
            "b7": float(np.interp(0.7, eps, bulge)) if done else math.nan, "wall_s": r.wall_s, "cached": r.cached}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--workers", type=int, default=2)
    a = ap.parse_args(argv)
    from flowcurve.identification.fe.pool import run_many

    jobs = [(mu, mesh, K) for mu in (0.1, 0.25) for mesh in MESHES.values() for K in (1000.0, 675.0)]
    t0 = time.perf_counter()
    out = dict(zip(jobs, run_many(run, jobs, workers=a.workers)))
    print(f"{len(jobs)} runs in {time.perf_counter() - t0:.0f} s ({sum(not r['cached'] for r in out.values())} not cached)")
    for mu in (0.1, 0.25):
        done = [m for m in MESHES.values() if math.isfinite(out[mu, m, 1000.0]["p"])]
        ref = out[mu, done[-1], 1000.0]
        print(f"\nμ = {mu}: ratios to the finest completed mesh ({[k for k, v in MESHES.items() if v == done[-1]][0]})")
        print(f"{'mesh (core / rim layer)':28s} {'p/K @0.7':>9s} {'ΔR/h @0.3':>10s} {'ΔR/h @0.7':>10s} {'ΔR/h σ/E ÷1.5':>14s} {'run s':>6s}")
        for name, mesh in MESHES.items():
            r, low = out[mu, mesh, 1000.0], out[mu, mesh, 675.0]
            print(f"{name:28s} {r['p'] / ref['p']:9.3f} {r['b3'] / ref['b3']:10.3f} {r['b7'] / ref['b7']:10.3f} "
                  f"{low['b7'] / r['b7'] - 1:+14.1%} {r['wall_s']:6.1f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
