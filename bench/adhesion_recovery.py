"""Do the adhesion fits' standard errors mean what they say? Repeat the virtual adhesiometer's
series with fresh noise and print, per constant, the bias, the scatter of the estimates, the
mean reported standard error and how often the truth lies within one standard error (≈ 68 %
if the errors are right).

    python bench/adhesion_recovery.py [REPEATS]
"""

from __future__ import annotations

import functools
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from flowcurve.identification.compression.adhesion import fit_refined, fit_simple
from flowcurve.record.adhesion import read_adhesion_table, write_adhesion_table
from flowcurve.rig.virtual.adhesiometer import FrictionTruth, VirtualAdhesiometer

TRUTH = FrictionTruth(tau0_MPa=80.0, beta0=0.05, k_b_per_C=1.0e-4, theta_k_C=650.0, mu_d=0.02)
COLD = list(np.geomspace(5.0, 1300.0, 24))
HOT = [200.0, 400.0, 800.0]

SIMPLE_EV = functools.partial(fit_simple, accuracy=(0.005, 0.5))
REFINED_EV_FINE = functools.partial(fit_refined, accuracy=(0.002, 0.2))
REFINED_EV = functools.partial(fit_refined, accuracy=(0.005, 0.5))
CASES = [
    # label, contact, moment noise, radius noise um, hot tests, fit, contact model
    ("full contact, simple, relative weights", "full", 0.005, 0.5, True, fit_simple, "none"),
    ("full contact, refined, relative weights", "full", 0.005, 0.5, True, fit_refined, "none"),
    ("full contact, simple, effective variance (0.5 %, 0.5 um)", "full", 0.005, 0.5, True, SIMPLE_EV, "none"),
    ("Bowden-Tabor, refined, 0.2 % / 0.2 um, effective variance", "bowden_tabor", 0.002, 0.2, False, REFINED_EV_FINE, "bowden_tabor"),
    ("Bowden-Tabor, refined, 0.5 % / 0.5 um, effective variance", "bowden_tabor", 0.005, 0.5, False, REFINED_EV, "bowden_tabor"),
]


def series(folder: Path, contact: str, noise: float, radius_noise: float, hot: bool, seed: int):
    device = VirtualAdhesiometer(truth=TRUTH, contact=contact, moment_noise_rel=noise, radius_noise_um=radius_noise, seed=seed)
    forces, temps = list(COLD), [20.0] * len(COLD)
    if hot:
        for t in (600.0, 700.0, 800.0):
            forces += HOT
            temps += [t] * len(HOT)
    data, _ = device.run_series(forces, temps)
    path = write_adhesion_table(folder / f"s{seed}.csv", data, device.table_meta())
    return read_adhesion_table(path), device.surface_flow_stress_MPa(20.0)


def main(repeats: int) -> None:
    truth = {"tau0_MPa": TRUTH.tau0_MPa, "beta0": TRUTH.beta0, "k_b_per_C": TRUTH.k_b_per_C, "theta_k_C": TRUTH.theta_k_C}
    with tempfile.TemporaryDirectory() as tmp:
        for label, contact, noise, radius_noise, hot, fit, model in CASES:
            start = time.perf_counter()
            rows = {k: [] for k in (*truth, "sigma_S_MPa")}
            for seed in range(repeats):
                table, flow = series(Path(tmp), contact, noise, radius_noise, hot, seed)
                result = fit(table, mu_d=TRUTH.mu_d, contact_model=model)
                keys = [*truth] if hot else ["tau0_MPa", "beta0"]
                if model == "bowden_tabor":
                    keys.append("sigma_S_MPa")
                for key in keys:
                    true = flow if key == "sigma_S_MPa" else truth[key]
                    rows[key].append((result.values[key], result.stderr[key] or np.nan, true))
            print(f"\n{label} ({repeats} series, {time.perf_counter() - start:.1f} s)")
            print(f"  {'constant':<12}{'truth':>11}{'mean':>11}{'bias/se':>9}{'sd':>11}{'mean se':>11}{'within 1 se':>13}")
            for key, values in rows.items():
                if not values:
                    continue
                est, se, true = (np.array(c, dtype=float) for c in zip(*values))
                inside = np.mean(np.abs(est - true) <= se)
                print(f"  {key:<12}{true[0]:>11.4g}{est.mean():>11.4g}{(est.mean() - true[0]) / np.nanmean(se):>9.2f}"
                      f"{est.std(ddof=1):>11.3g}{np.nanmean(se):>11.3g}{100 * inside:>12.0f}%")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 40)
