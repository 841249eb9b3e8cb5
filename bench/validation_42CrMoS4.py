"""Validation of the tension identification against the 42CrMoS4 lab's published values.

All 67 INSTRON exports of tests/data/42CrMoS4/original_data/ (CC BY 4.0, in the repository) are read through
flowcurve.record.importers.load_record and identified twice:

* extensometer path (the lab's own route): E, Rp0.2, Rm, Ag, A, Z against the header values;
* crosshead-only path: the "Machine Displacement" channel, frame compliance removed with a
  stiffness identified from specimens of known modulus (handbook E of steel, 210 GPa) — the
  way a lab without an extensometer would work. Leave-one-out: each specimen is corrected
  with the median stiffness calibrated on the 66 others, so its own data never set its C.
  Then the same channel without any compliance correction, for contrast.

Run: python bench/validation_42CrMoS4.py  (prints the summary table; ~20 s)
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

from flowcurve.errors import FlowcurveError
from flowcurve.record.importers import load_record
from flowcurve.identification.indicator import frame_stiffness_from_known_modulus
from flowcurve.identification.tension.identify import identify_tension

# the validation set travels with the repository (tests/data/42CrMoS4: its README and LICENSE)
DATA = Path(__file__).resolve().parents[1] / "tests" / "data" / "42CrMoS4" / "original_data"
HANDBOOK_E_MPa = 210_000.0  # steel, for the one-off frame calibration of the crosshead path

# quantity → (result key, published key, kind of deviation, acceptance limit of the brief)
QUANTITIES = {
    "E": ("E_MPa", "published.E_MPa", "rel", 0.02),
    "Rp0.2": ("Rp02_MPa", "published.Rp02_MPa", "rel", 0.005),
    "Rm": ("Rm_MPa", "published.Rm_MPa", "rel", 0.005),
    "Ag": ("Ag_pct", "published.Ag_pct", "abs", 0.5),
    "A": ("A_pct", "published.A_pct", "abs", 0.5),
    "Z": ("Z_pct", "published.Z_pct", "abs", 0.5),
}


def specimen_files() -> list[Path]:
    return sorted(DATA.glob("*.csv"))


def calibrate_frame(path: Path, E_MPa: float = HANDBOOK_E_MPa) -> float:
    """Frame stiffness (N/µm) from one specimen taken as of known modulus, over 10–50 % Rm."""
    rec = load_record(path)
    force = rec.column("force_N")
    cross = rec.column("crosshead_mm")
    s0 = rec.positive("specimen.s0_mm2", required=True)
    Fm = float(np.max(force))
    return frame_stiffness_from_known_modulus(cross, force, E_MPa=E_MPa, area_mm2=s0,
                                              length_mm=rec.positive("specimen.parallel_length_mm", required=True),
                                              window_N=(0.1 * Fm, 0.5 * Fm))


def deviations(files, per_file_options=None, **options) -> tuple[dict[str, np.ndarray], list[str]]:
    """Per quantity, the deviation of each specimen from its published value (relative for
    stresses and E, percentage points for Ag, A, Z; NaN where the identification failed),
    and the failures as 'specimen: message'."""
    out: dict[str, list[float]] = {q: [] for q in QUANTITIES}
    failures = []
    for i, path in enumerate(files):
        rec = load_record(path)
        extra = per_file_options[i] if per_file_options else {}
        try:
            res = identify_tension(rec, **options, **extra).result
        except FlowcurveError as exc:
            failures.append(f"{path.stem}: {exc}")
            for q in QUANTITIES:
                out[q].append(np.nan)
            continue
        for q, (key, pub, kind, _) in QUANTITIES.items():
            ours, theirs = res[key], rec.number(pub, required=True)
            out[q].append(ours / theirs - 1.0 if kind == "rel" else ours - theirs)
    return {q: np.array(v) for q, v in out.items()}, failures


def leave_one_out_stiffness(files) -> np.ndarray:
    """For each specimen, the median frame stiffness calibrated on all the others (N/µm)."""
    each = np.array([calibrate_frame(f) for f in files])
    return np.array([np.median(np.delete(each, i)) for i in range(each.size)]), each


def summary(dev: dict[str, np.ndarray]) -> dict[str, dict[str, float]]:
    table = {}
    for q, (_, _, kind, limit) in QUANTITIES.items():
        a = np.abs(dev[q])
        a = np.where(np.isfinite(a), a, np.inf)  # a failed identification fails every quantity
        scale = 100.0 if kind == "rel" else 1.0  # relative → %
        ok = a[np.isfinite(a)]
        table[q] = {"pass_rate": float(np.mean(a <= limit)), "median": float(np.median(ok) * scale) if ok.size else float("nan"),
                    "max": float(np.max(ok) * scale) if ok.size else float("nan"), "limit": limit * scale, "unit": "%" if kind == "rel" else "pp"}
    return table


def print_table(title: str, table: dict, failures: list[str] = ()) -> None:
    print(f"\n{title}")
    if failures:
        print(f"  {len(failures)} specimen(s) could not be identified (counted as failing), e.g. {failures[0]}")
    print(f"{'quantity':<9}{'limit':>10}{'pass':>9}{'median |dev|':>15}{'max |dev|':>12}")
    for q, row in table.items():
        print(f"{q:<9}{row['limit']:>7.3g} {row['unit']:<2}{100 * row['pass_rate']:>8.1f}%{row['median']:>12.3f} {row['unit']:<2}{row['max']:>9.3f} {row['unit']}")


def main() -> int:
    files = specimen_files()
    if not files:
        print(f"no data in {DATA}", file=sys.stderr)
        return 1
    t0 = time.perf_counter()
    dev, fail = deviations(files)
    print_table(f"Extensometer path ({len(files)} specimens; E over the automatic window, the widest linear stretch; the lab used 10-80 % of Rp0.2)", summary(dev), fail)
    t1 = time.perf_counter()
    loo, each = leave_one_out_stiffness(files)
    print(f"\nframe stiffness per specimen taken as E = {HANDBOOK_E_MPa / 1000:g} GPa: median {np.median(each):.1f} N/um, "
          f"range {each.min():.1f}-{each.max():.1f} N/um (specimen compliance is ~1/3 of the frame's)")
    dev, fail = deviations(files, [{"frame_stiffness_N_per_um": c} for c in loo], use_extensometer=False)
    print_table("Crosshead-only path, compliance removed (leave-one-out median C), strain on the parallel length", summary(dev), fail)
    dev, fail = deviations(files, use_extensometer=False)
    print_table("Crosshead-only path, no compliance correction", summary(dev), fail)
    t2 = time.perf_counter()
    print(f"\nidentification time: {1000 * (t1 - t0) / len(files):.0f} ms per specimen (extensometer path); "
          f"crosshead paths {1000 * (t2 - t1) / (2 * len(files)):.0f} ms per specimen, ratio {((t2 - t1) / 2) / (t1 - t0):.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
