"""Benchmark: identify a one-hour record (150 Hz, 540 000 rows) against merely reading it.

Writes a synthetic tension record in the native format (a Johnson–Cook material on a
136 N/µm frame, with noise), then times in the same run:

  (a) pandas.read_csv of the file alone — the reference,
  (b) load_record (the flowcurve reader),
  (c) identify (no plots), and (d) add_plots + write (PNGs, result.json, true_curve.csv).

Prints the figures and the ratio identify / read; the target is at most 2 (issue 43).
Run: python bench/identify_long_record.py [--rows N] [--repeat K]
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd

from flowcurve.record.format import Record, write_record
from flowcurve.identification.identify import identify
from flowcurve.record.importers import load_record
from flowcurve.reports.plots import add_plots

D0_MM, L0_MM, E_MPA = 6.0, 30.0, 200e3
A_MPA, B_MPA, N = 300.0, 600.0, 0.35
FRAME_N_PER_UM = 136.0
EPS_F = 0.8  # true fracture strain ln(F0/Fk)


def synthetic_tension(rows: int, rate_hz: float = 150.0, seed: int = 0) -> Record:
    """A tension record from a known law: uniform hardening to Rm, then a falling neck branch.

    post.lu_mm is what a caliper reads on the unloaded pieces: L0 plus the elongation at the
    fracture less the elastic extension the uniform part gives back, L0·e^εu·(e^(σ_f/E) − 1) with
    σ_f = F_f·e^εu/S0 on its plastic section (the neck's own, over its short length, is left out).
    """
    rng = np.random.default_rng(seed)
    t = np.arange(rows) / rate_hz
    area = np.pi * D0_MM**2 / 4
    n_el = rows // 30  # the first 2 minutes: elastic loading up to A
    eps_p = np.concatenate([np.zeros(n_el), np.linspace(0.0, 0.45, rows - n_el)])  # Considère at εp ≈ n
    sig_t = A_MPA + B_MPA * eps_p**N
    sig_t[:n_el] = A_MPA * np.linspace(0.0, 1.0, n_el, endpoint=False)
    eps = eps_p + sig_t / E_MPA  # true strain: plastic + elastic
    eng = np.exp(eps) - 1.0
    force = sig_t * area / (1.0 + eng)  # P = σ_t·F0/(1 + e), volume constancy
    i_m = int(np.argmax(force))
    # past maximum force the neck carries less and less, down to the force at fracture
    tail = np.linspace(0.0, 1.0, rows - i_m)
    drop = 1.0 - fracture_force(EPS_F, float(eps_p[i_m])) / force[i_m]
    force[i_m:] = force[i_m] * (1.0 - drop * tail**1.5)
    elong = eng * L0_MM
    elong[i_m:] = elong[i_m] + (elong[-1] - elong[i_m]) * tail * 0.6
    crosshead = elong + force / (FRAME_N_PER_UM * 1e3)
    eps_u = float(eps_p[i_m])
    recovery = L0_MM * np.exp(eps_u) * np.expm1(force[-1] * np.exp(eps_u) / area / E_MPA)  # the pieces' elastic give-back, mm
    dk = float(D0_MM * np.exp(-EPS_F / 2.0))
    data = pd.DataFrame({
        "time_s": t,
        "force_N": force + rng.normal(0.0, 3.0, rows),
        "crosshead_mm": crosshead + rng.normal(0.0, 5e-4, rows),
    })
    meta = {"flowcurve-record": "1", "status": "complete", "test": "tension", "material": "synthetic JC",
            "specimen.id": "bench-1h", "nominal_temperature_C": "20", "crosshead_speed_mm_per_s": repr(float(crosshead[-1] / t[-1])),
            "rig.frame_stiffness_N_per_um": repr(FRAME_N_PER_UM), "specimen.d0_mm": repr(D0_MM), "specimen.l0_mm": repr(L0_MM),
            "specimen.parallel_length_mm": repr(L0_MM),  # the crosshead stretches L0: Lc = L0
            "post.lu_mm": repr(float(L0_MM + elong[-1] - recovery)), "post.dk_mm": repr(dk)}
    return Record(meta=meta, data=data, source="bench")


def fracture_force(eps_f: float, eps_u: float) -> float:
    """Force at fracture for which the Davidenkov-corrected stress lies on the law itself.

    Fk = π dk²/4 with εf = 2·ln(d0/dk) (3.13); a/R = 1.1·(εf − εu) (Le Roy);
    Sk = P/Fk · 1/(1 + a/(4R)) (3.10)-(3.11) set equal to A + B·εf^n.
    """
    dk = D0_MM * np.exp(-eps_f / 2.0)
    return float((A_MPA + B_MPA * eps_f**N) * np.pi * dk**2 / 4 * (1.0 + 1.1 * (eps_f - eps_u) / 4.0))


def best_of(repeat: int, func):
    times, value = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        value = func()
        times.append(time.perf_counter() - t0)
    return min(times), value


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rows", type=int, default=540_000, help="samples (default: 1 h at 150 Hz)")
    parser.add_argument("--repeat", type=int, default=3, help="take the best of this many runs")
    parser.add_argument("--profile", action="store_true", help="print the top functions of identify")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "long.csv"
        write_record(path, synthetic_tension(args.rows))
        size_mb = path.stat().st_size / 1e6
        t_read, _ = best_of(args.repeat, lambda: pd.read_csv(path, comment="#"))
        t_load, record = best_of(args.repeat, lambda: load_record(path))
        t_ident, ident = best_of(args.repeat, lambda: identify(record))
        t_window, _ = best_of(args.repeat, lambda: identify(record, modulus_method="window"))  # the project's own window method instead of SDAR
        short = Path(tmp) / "short.csv"  # a hundredth of the record: what identify costs whatever the length (the hardening fits on 30 points)
        write_record(short, synthetic_tension(args.rows // 100))
        short_record = load_record(short)
        t_short, _ = best_of(args.repeat, lambda: identify(short_record))
        fresh = identify(record)
        t_plots, _ = best_of(1, lambda: add_plots(fresh).write(Path(tmp) / "out"))
        if args.profile:
            prof = cProfile.Profile()
            prof.runcall(identify, record)
            pstats.Stats(prof).sort_stats("cumulative").print_stats(15)
    res = ident.result
    h = res.get("hardening", {})
    print(f"record: {args.rows} rows, {size_mb:.1f} MB")
    print(f"(a) pandas.read_csv alone      {t_read * 1e3:8.1f} ms   (reference)")
    print(f"(b) load_record                {t_load * 1e3:8.1f} ms   ratio to (a) {t_load / t_read:5.2f}")
    print(f"(c) identify, no plots         {t_ident * 1e3:8.1f} ms   ratio to (a) {t_ident / t_read:5.2f}   target ≤ 2")
    print(f"(c') identify, --modulus-method window {t_window * 1e3:7.1f} ms   ratio to (a) {t_window / t_read:5.2f}   (the project's own window instead of SDAR)")
    print(f"(c'') identify, {args.rows // 100} rows     {t_short * 1e3:8.1f} ms   ratio to (a) {t_short / t_read:5.2f}   (the part that does not grow with the record)")
    print(f"(d) plots + write (on top)     {t_plots * 1e3:8.1f} ms   ratio to (a) {t_plots / t_read:5.2f}")
    print(f"identified: Rm {res.get('Rm_MPa', float('nan')):.1f} MPa, A {h.get('A_MPa', float('nan')):.1f} MPa "
          f"(true {A_MPA:g}), B {h.get('B_MPa', float('nan')):.1f} MPa (true {B_MPA:g}), n {h.get('n', float('nan')):.3f} (true {N:g})")


if __name__ == "__main__":
    main()
