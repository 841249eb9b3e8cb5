"""Does the stated U hold the truth, and is it no blanket? (issue 43) — on records whose truth is known.

* closed-form crosshead-only tension (bench/modulus_methods.crosshead_tension: Voce law, frames 10.8–136 N/µm,
  toes 0–0.2 mm; the truth the diagram's own Rp0.2 with its elastic slope, and Rm);
* closed-form compression with a seating toe (tests/compression/toe_records.py: slab model, the seed law; the
  truth the model's mean pressure at εp 0.002), without material.E_MPa and named 12Kh18N12M3TL;
* the held-out upsetting record's look-alikes (tests/uncertainty/data: CalculiX C1 on a toe; truth 131–135.5 MPa).

Per kind: the share of records whose |value − truth| ≤ U, the median U and the median |error| (their ratio:
"a few" is no blanket) — with the method's share and without it (u² − u_method², the budget before issue 43).
Run: nice python bench/budget_coverage.py  (~1 min)
"""

from __future__ import annotations

import math
import runpy
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from flowcurve.identification.quality.assurance import attach  # noqa: E402
from flowcurve.identification.compression.identify import identify_compression  # noqa: E402
from flowcurve.identification.tension.identify import identify_tension  # noqa: E402
from flowcurve.record.format import read_record  # noqa: E402

MODULUS = runpy.run_path(str(ROOT / "bench" / "modulus_methods.py"))


def _row(kind, value, truth, b):
    lo, hi = truth if isinstance(truth, tuple) else (truth, truth)
    err = 0.0 if lo <= value <= hi else min(abs(value - lo), abs(value - hi))
    u_old = math.sqrt(max(b["u"] ** 2 - b.get("u_method", 0.0) ** 2, 0.0))
    return {"kind": kind, "err": err, "U": b["U"], "U_old": 2.0 * u_old}


def tension_rows() -> list[dict]:
    rows = []
    for i, case in enumerate(MODULUS["CROSSHEAD_CASES"]):
        rec, _, rp02 = MODULUS["crosshead_tension"](**case)
        ident = identify_tension(rec)
        attach(ident.result, ident.curves, rec)
        unc = ident.result["uncertainty"]
        rows.append(_row("tension crosshead Rp0.2", ident.result["Rp02_MPa"], rp02, unc["Rp02_MPa"]))
        rm_truth = float(rec.meta.get("truth.Rm_MPa", "nan")) if "truth.Rm_MPa" in rec.meta else None
        if rm_truth:
            rows.append(_row("tension crosshead Rm", ident.result["Rm_MPa"], rm_truth, unc["Rm_MPa"]))
    return rows


def compression_rows() -> list[dict]:
    from tests.compression.toe_records import make_toe_compression

    rows = []
    for toe in (0.0, 0.05):
        for rate in (2.0, 10.0):
            for seed in (1, 2):
                rec, truth = make_toe_compression(toe_mm=toe, rate_hz=rate, seed=seed)
                rec.meta["material"] = "12Kh18N12M3TL"
                rec.meta.pop("material.E_MPa", None)
                ident = identify_compression(rec)
                attach(ident.result, ident.curves, rec)
                if ident.result.get("Rp02_MPa") is not None:
                    rows.append(_row("compression closed form Rp0.2", ident.result["Rp02_MPa"], truth["rp02_pressure_MPa"],
                                     ident.result["uncertainty"]["Rp02_MPa"]))
    for path in sorted((ROOT / "tests" / "uncertainty" / "data").glob("upsetting_*.csv")):
        rec = read_record(path)
        ident = identify_compression(rec)
        attach(ident.result, ident.curves, rec)
        rows.append(_row("CalculiX upsetting look-alike Rp0.2", ident.result["Rp02_MPa"], (131.0, 135.5), ident.result["uncertainty"]["Rp02_MPa"]))
    return rows


def main() -> int:
    rows = tension_rows() + compression_rows()
    print(f"{'kind':<38}{'n':>4}{'held':>7}{'held before':>13}{'med |err|':>11}{'med U':>9}{'U/err':>8}{'med U before':>14}")
    for kind in dict.fromkeys(r["kind"] for r in rows):
        sel = [r for r in rows if r["kind"] == kind]
        err = np.array([r["err"] for r in sel])
        U, U_old = np.array([r["U"] for r in sel]), np.array([r["U_old"] for r in sel])
        med_err = float(np.median(err))
        ratio = float(np.median(U)) / med_err if med_err > 0 else math.inf
        print(f"{kind:<38}{len(sel):>4}{100 * np.mean(err <= U):>6.0f}%{100 * np.mean(err <= U_old):>12.0f}%{med_err:>11.3g}"
              f"{np.median(U):>9.3g}{ratio:>8.3g}{np.median(U_old):>14.3g}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
