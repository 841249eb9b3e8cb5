"""The friction law's form: records whose end face is two Coulomb zones (tests/fe/zoned_friction.py, the second
model's deck with μ_center inside 0.7·r0 and μ_rim beyond and on the side; C1, C3, S4's laws and specimens, a
lubricated centre 0.5·μ / 1.5·μ and a dry centre 1.5·μ / 0.5·μ), read by the product's defaults
(identification.identify on record.importers.load_record).

    PYTHONPATH=. python bench/zoned_friction.py [--records tests/fe/data]

Per record: the mean μ of the initial face (the truth, fe2.mu) and the zones'; μ from the end face and from the
bulge ± their standard errors (friction_details.fe_table), |μ − mean|/U of uncertainty.friction_mu; per flow-stress
point (εp 0.05 0.1 0.2 0.3 0.5) the error % of A + B·εpⁿ, the correction's stated σ % (true_curve.csv
correction_uncertainty_pct) and |error|/U; the hardening constants' |error|/U against the law fitted over the
result's fit range; W: result.json warns that the end face and the bulge disagree; ΔF: the peak force against the
uniform-μ record of the same specimen at the same crosshead (second_model_<C1|C3|S4>.csv, μ the zones' 1.0·μ). Then the realised flow-stress
error per μ, max|error %|/(100·μ), against the 0.12·μ the product states. The measured table is in
docs/methods.md §4a.7.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from flowcurve.record.format import read_record  # noqa: E402
from tests.fe.zoned_friction import measure  # noqa: E402


def _loading(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """(crosshead mm, force N) of a record's loading branch, compression positive."""
    d = read_record(path).data
    f, x = -d["force_N"].to_numpy(float), -d["crosshead_mm"].to_numpy(float)
    i = int(np.argmax(f))
    return x[: i + 1], f[: i + 1]


def force_against_uniform(zoned: Path, uniform: Path) -> float:
    """The zoned record's peak force against the uniform record's force at the same crosshead position, %."""
    xz, fz = _loading(zoned)
    xu, fu = _loading(uniform)
    return 100.0 * (fz[-1] / float(np.interp(xz[-1], xu, fu)) - 1.0)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--records", type=Path, default=ROOT / "tests" / "fe" / "data")
    args = ap.parse_args(argv)
    uniform = sorted(args.records / f"second_model_{b}.csv" for b in ("C1", "C3", "S4"))  # the same specimens, one μ: the reference
    paths = sorted(args.records.glob("zoned_*.csv")) + uniform
    rows = [measure(p) for p in paths]
    dF = [force_against_uniform(p, args.records / f"second_model_{r['record'][:2]}.csv") for p, r in zip(paths, rows)]
    ref, rows, dF = rows[len(paths) - len(uniform):], rows[: len(paths) - len(uniform)], dF[: len(paths) - len(uniform)]
    print("record  μ mean (c/r)        | μ face ± se     μ bulge ± se    |Δμ|/U W | flow error % (σ_corr %) [|err|/U] at εp 0.05 0.1 0.2 0.3 0.5"
          " | max|err|/(100μ) | max|err|/σ_corr | ΔF % | constants |err|/U")
    ratios, zs, zmu, zc = [], [], [], []
    for r, df in zip(rows, dF):
        face = f"{r['mu_face']:.3f} ± {r['mu_face_se']:.3f}" if r["mu_face"] is not None else "      —      "
        pts = " ".join(f"{p['error_pct']:+.2f} ({p['u_corr_pct']:.1f}) [{p['z']:.2f}]" for p in r["points"])
        worst = max(abs(p["error_pct"]) for p in r["points"]) / (100.0 * r["mu_true"])
        ratios.append(worst)
        per_sigma = max(abs(p["error_pct"]) / p["u_corr_pct"] for p in r["points"])
        zs += [p["z"] for p in r["points"]]
        zmu.append(abs(r["mu"] - r["mu_true"]) / r["mu_U"])
        zc += [c["z"] for c in r["constants"]]
        cons = " ".join(f"{c['name']} {c['z']:.2f}" for c in r["constants"])
        print(f"{r['record']:6s}  {r['mu_true']:.3f} ({r['mu_center']:.3f}/{r['mu_rim']:.3f}) | {face}  {r['mu_bulge']:.3f} ± {r['mu_bulge_se']:.3f}  "
              f"{zmu[-1]:5.2f} {'W' if r['disagree_warning'] else '-'} | {pts} | {worst:.3f}·μ | {per_sigma:.2f} | {df:+.2f} | {cons}")
    print(f"\nflow-stress error per μ, max|err %|/(100·μ): {min(ratios):.3f}–{max(ratios):.3f} (stated σ 0.12·μ)")
    ref_ratio = [max(abs(p["error_pct"]) for p in r["points"]) / (100.0 * r["mu_true"]) for r in ref]
    print("uniform μ, the same specimens (second_model_C1/C3/S4): max|err %|/(100·μ) " + ", ".join(f"{r['record']} {x:.3f}" for r, x in zip(ref, ref_ratio))
          + "; max|err|/σ_corr " + ", ".join(f"{max(abs(p['error_pct']) / p['u_corr_pct'] for p in r['points']):.2f}" for r in ref)
          + "; curve " + ", ".join(f"{100 * r['curve_error']:.2f} %" for r in ref))
    print("the curve's largest |σ/σ_true − 1| over εp 0.05–0.6: " + ", ".join(f"{r['record']} {100 * r['curve_error']:.2f} %" for r in rows))
    print(f"flow stress: value ± U holds the truth at {sum(z <= 1 for z in zs)} of {len(zs)} points (largest |err|/U {max(zs):.2f})")
    print(f"μ: value ± U holds the mean μ on {sum(z <= 1 for z in zmu)} of {len(zmu)} (largest {max(zmu):.2f})")
    print(f"constants: value ± U holds the fitted truth for {sum(z <= 1 for z in zc)} of {len(zc)} (largest {max(zc, default=0):.2f})")
    print(f"the end face and the bulge warned as disagreeing on {sum(r['disagree_warning'] for r in rows)} of {len(rows)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
