"""Two CalculiX executables on the same upsetting decks: force, barrel, speed and the fold-over.

    python bench/ccx_versions.py --other PATH [--workers 2] [--stopped-every 3]

``--other`` is a second ccx (say a newer build); the first is the one the product runs
(``FLOWCURVE_CCX``, else ``ccx``). Part 1 runs the Voce record's specimen (d0 5, h0 9 mm to
ε 0.7, its law) at μ 0, 0.1, 0.17 and 0.2 on the default mesh (24 core elements), and at μ 0.1
on 36 and 48 (the two solvers' answers should meet as the mesh is refined): printed, per
executable, whether the run completed, the force at ε 0.3/0.5/0.7, dmax at the end and the wall
time, then the other's force over the first's. Part 2 runs every K-th of the FE table's runs
that stopped where the side folds onto the platen (``incomplete_runs`` in
``upsetting_table.json``, the furthest of four tries with the first executable) once with the
other: completed, farther or shorter. A private temporary run cache, so the times are real.
"""

from __future__ import annotations

import argparse
import math
import os
import tempfile
import time

import numpy as np

STRAINS = (0.3, 0.5, 0.7)
VOCE_CASE = 3  # synthetic.VALIDATION_CASES: Voce, h0/d0 1.8, the record whose inverse runs stop near μ 0.2


def voce_run(args):
    from flowcurve.identification.fe.synthetic import VALIDATION_CASES, case_flow
    from flowcurve.identification.fe.model.upsetting import UpsettingModel, simulate_upsetting

    exe, mu, nr, increments = args
    os.environ["FLOWCURVE_CCX"] = exe
    c = VALIDATION_CASES[VOCE_CASE]
    m = UpsettingModel.from_law(c["d0"], c["h0"], c["h0"] * math.exp(-c["eps_end"]), mu, case_flow(c), E_MPa=c["E"],
                                increments=increments, nr=nr, layer_fraction=1.0 / nr)
    r = simulate_upsetting(m, require_complete=False)
    eps = np.log(c["h0"] / r.height_mm)
    force = [float(np.interp(e, eps, r.force_N)) if eps[-1] >= e - 1e-9 else math.nan for e in STRAINS]
    return {"completed": bool(r.completed), "force": force, "dmax": float(r.dmax_mm[-1]) if r.completed else math.nan,
            "wall_s": r.wall_s}


def table_run(args):
    from flowcurve.identification.fe.make_table import grid_model
    from flowcurve.identification.fe.model.upsetting import simulate_upsetting

    exe, case = args
    os.environ["FLOWCURVE_CCX"] = exe
    r = simulate_upsetting(grid_model(case["mu"], case["h0_d0"], case["n"], case["eps0"]), require_complete=False)
    return {"completed": bool(r.completed), "reached": float(r.strain[-1]) if r.strain.size else 0.0, "wall_s": r.wall_s}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--other", required=True, help="the second ccx executable")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--stopped-every", type=int, default=3, help="run every K-th of the table's stopped runs (0: none)")
    a = ap.parse_args(argv)
    from flowcurve.identification.fe.model.ccx import ccx_executable, ccx_version
    from flowcurve.identification.fe.pool import run_many

    first = ccx_executable()
    os.environ["FLOWCURVE_CCX"] = a.other
    other, other_version = ccx_executable(), ccx_version()
    os.environ["FLOWCURVE_CCX"] = first
    names = {first: ccx_version(), other: other_version}
    os.environ["FLOWCURVE_FE_CACHE"] = tempfile.mkdtemp(prefix="flowcurve-ccx-versions-")

    settings = [(mu, 24, 50) for mu in (0.0, 0.1, 0.17, 0.2)] + [(0.1, 36, 75), (0.1, 48, 100)]
    jobs = [(exe, *s) for s in settings for exe in (first, other)]
    t0 = time.perf_counter()
    out = dict(zip(jobs, run_many(voce_run, jobs, workers=a.workers)))
    print(f"Voce record's specimen: {len(jobs)} runs in {time.perf_counter() - t0:.0f} s")
    print(f"{'μ':>5s} {'mesh':>4s} {'inc':>4s} {'ccx':>9s} {'done':>5s} " + " ".join(f"{'F_N @' + str(e):>9s}" for e in STRAINS)
          + f" {'dmax mm':>8s} {'wall s':>7s}   other/first − 1 (force)")
    for s in settings:
        for exe in (first, other):
            r = out[(exe, *s)]
            ratio = ""
            if exe == other:
                ratio = " ".join(f"{f / g - 1:+.2%}" for f, g in zip(r["force"], out[(first, *s)]["force"]))
            print(f"{s[0]:5.2f} {s[1]:4d} {s[2]:4d} {names[exe]:>9s} {str(r['completed']):>5s} "
                  + " ".join(f"{f:9.0f}" for f in r["force"]) + f" {r['dmax']:8.4f} {r['wall_s']:7.1f}   {ratio}")

    if a.stopped_every > 0:
        from flowcurve.identification.fe.model.table import PACKAGE_TABLE, table_provenance

        table = table_provenance(PACKAGE_TABLE)
        stopped = table["incomplete_runs"][:: a.stopped_every]
        t0 = time.perf_counter()
        res = run_many(table_run, [(other, c) for c in stopped], workers=a.workers)
        print(f"\nthe table's stopped runs ({table['ccx_version']}, best of four tries): {len(stopped)} of "
              f"{len(table['incomplete_runs'])} run once with {names[other]} in {time.perf_counter() - t0:.0f} s")
        tally = {"completed": 0, "farther": 0, "shorter": 0}
        for c, r in zip(stopped, res):
            kind = "completed" if r["completed"] else "farther" if r["reached"] > c["reached_strain"] else "shorter"
            tally[kind] += 1
            print(f"  μ {c['mu']:.2f} h0/d0 {c['h0_d0']:.1f} n {c['n']:.2f} ε0 {c['eps0']:g}: reached ε {c['reached_strain']:.3f}"
                  f" → {r['reached']:.3f} ({kind}, {r['wall_s']:.0f} s)")
        print("  " + ", ".join(f"{v} {k}" for k, v in tally.items()))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
