"""The crosshead compliance model's own uncertainty on Rp0.2, from extensometer pairs (issue 43).

Each of the 67 42CrMoS4 INSTRON exports (tests/data/42CrMoS4, real, CC BY 4.0) carries both the
extensometer and the crosshead ("Machine Displacement"). Rp0.2 is identified from each channel of
the same specimen: the extensometer's is the reference, the crosshead's the crosshead-only record
a lab without an extensometer would have. Two crosshead paths: the default (no frame stiffness:
the offset line parallel to the diagram's slope, ISO 6892-1) and the frame compliance removed with
a leave-one-out stiffness calibrated on the other 66 specimens at E = 210 GPa.

Prints, per path, the relative differences crosshead − extensometer (mean, standard deviation,
rms, largest) and the coverage of the stated U; the rms of the default path is
identification.uncertainty.CROSSHEAD_RP_REL_U (docs/methods.md §2.12).

Run: nice python bench/crosshead_pairs_42CrMoS4.py  (~2 min)
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from validation_42CrMoS4 import leave_one_out_stiffness, specimen_files  # noqa: E402

from flowcurve.identification.quality.assurance import attach  # noqa: E402
from flowcurve.identification.tension.identify import identify_tension  # noqa: E402
from flowcurve.identification.quality.uncertainty import CROSSHEAD_RP_REL_U  # noqa: E402
from flowcurve.record.importers import load_record  # noqa: E402


def pairs(files, stiffness=None) -> list[dict]:
    """Per specimen: the extensometer's Rp0.2 and the crosshead's with its stated U (stiffness per file, or none)."""
    rows = []
    for i, path in enumerate(files):
        rec = load_record(path)
        ext = identify_tension(rec).result["Rp02_MPa"]
        kw = {} if stiffness is None else {"frame_stiffness_N_per_um": float(stiffness[i])}
        ident = identify_tension(rec, use_extensometer=False, **kw)
        attach(ident.result, ident.curves, rec)
        rows.append({"name": path.stem, "ext": ext, "xh": ident.result["Rp02_MPa"], "U": ident.result["uncertainty"]["Rp02_MPa"]["U"]})
    return rows


def summary(rows: list[dict]) -> dict:
    rel = np.array([r["xh"] / r["ext"] - 1.0 for r in rows])
    held = np.array([abs(r["xh"] - r["ext"]) <= r["U"] for r in rows])
    return {"n": rel.size, "mean_pct": 100 * rel.mean(), "sd_pct": 100 * rel.std(ddof=1), "rms_pct": 100 * np.sqrt(np.mean(rel**2)),
            "max_pct": 100 * np.max(np.abs(rel)), "held": float(held.mean()),
            "median_U_pct": 100 * float(np.median([r["U"] / r["xh"] for r in rows])), "median_err_pct": 100 * float(np.median(np.abs(rel)))}


def main() -> int:
    files = specimen_files()
    loo, _ = leave_one_out_stiffness(files)
    print(f"crosshead − extensometer Rp0.2 over {len(files)} specimens of 42CrMoS4 (CROSSHEAD_RP_REL_U = {100 * CROSSHEAD_RP_REL_U:.2f} %)")
    print(f"{'path':<44}{'mean %':>8}{'sd %':>7}{'rms %':>7}{'max %':>7}{'held':>7}{'med U %':>9}{'med err %':>10}")
    for label, stiffness in (("no frame stiffness (default)", None), ("frame removed, leave-one-out stiffness", loo)):
        s = summary(pairs(files, stiffness))
        print(f"{label:<44}{s['mean_pct']:>8.2f}{s['sd_pct']:>7.2f}{s['rms_pct']:>7.2f}{s['max_pct']:>7.2f}{100 * s['held']:>6.0f}%"
              f"{s['median_U_pct']:>9.2f}{s['median_err_pct']:>10.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
