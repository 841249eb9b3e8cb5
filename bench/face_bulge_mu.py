"""μ from the end face against μ from the bulge on every vendored compression record that carries both dface and dmax
(tests/fe/data: second_model_*.csv and other_settings_*.csv, one uniform Coulomb μ; zoned_*.csv, the end face in two
Coulomb zones, L a lubricated centre, D a dry one), read by the product's defaults (tests/fe/zoned_friction.measure:
identification.identify on record.importers.load_record).

    PYTHONPATH=. python bench/face_bulge_mu.py [--records tests/fe/data]

Per record: μ_face ± se and μ_bulge ± se (friction_details.fe_table: mu / mu_stderr and mu_from_bulge /
mu_from_bulge_stderr); z = |face − bulge| / √(se_f² + se_b²) (face_bulge_disagreement_sigmas); s = (bulge − face) /
√(se_f² + se_b²), the signed difference; r = (bulge − face) / face; the truth (uniform: fe2.mu; zoned: the face's
area-weighted mean fe2.mu, the centre's and the rim's); |μ − truth|/U of uncertainty.friction_mu (the mean for
zoned; ≤ 1: μ ± U holds it); the warnings of friction (W: face and bulge disagree, Z: a face of unequal zones).
Then each rule's margin under the readings' resolution: the same figures with dface or dmax read one step
(0.01 mm, friction.DIAMETER_RESOLUTION_MM) off either way (four copies of each record), per record the least and
largest s, r and t = (bulge − face)/se_b. Deterministic: no random draws; the records are vendored. The measured table is in docs/methods.md §4.9.
"""

from __future__ import annotations

import argparse
import math
import shutil
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from flowcurve.identification.compression.friction import DIAMETER_RESOLUTION_MM  # noqa: E402
from flowcurve.record.format import amend_record, read_record  # noqa: E402
from tests.fe.zoned_friction import measure  # noqa: E402

KINDS = ("second_model", "other_settings", "zoned")


def records(folder: Path) -> list[Path]:
    """The vendored compression records with both dface and dmax, uniform first."""
    out = []
    for kind in KINDS:
        for p in sorted(folder.glob(f"{kind}_*.csv")):
            head = p.read_text(encoding="utf-8").split("\ntime_s", 1)[0]
            if "post.dface_mm" in head and "post.dmax_mm" in head:
                out.append(p)
    return out


def row(path: Path) -> dict:
    """One record's figures (see the module's docstring)."""
    m = measure(path)
    face, se_f, bulge, se_b = m["mu_face"], m["mu_face_se"], m["mu_bulge"], m["mu_bulge_se"]
    se = math.hypot(se_f, se_b)
    zoned = m["mu_center"] != m["mu_rim"]
    return {"name": path.stem, "zoned": zoned, "dry": zoned and m["mu_center"] > m["mu_rim"], "face": face, "se_f": se_f,
            "bulge": bulge, "se_b": se_b, "z": abs(bulge - face) / se, "s": (bulge - face) / se, "r": (bulge - face) / face, "t": (bulge - face) / se_b,
            "truth": m["mu_true"], "center": m["mu_center"], "rim": m["mu_rim"], "mu": m["mu"], "U": m["mu_U"],
            "zU": abs(m["mu"] - m["mu_true"]) / m["mu_U"],
            "W": m["disagree_warning"], "Z": any(w.startswith("friction: the end face and the bulge disagree as") for w in m["warnings"])}


def off_by_resolution(path: Path) -> list[dict]:
    """:func:`row` of the record with dface, then dmax, read one resolution step low and high."""
    meta = read_record(path).meta
    out = []
    with tempfile.TemporaryDirectory() as tmp:
        for key in ("post.dface_mm", "post.dmax_mm"):
            for sign in (-1.0, 1.0):
                copy = Path(tmp) / path.name
                shutil.copyfile(path, copy)
                amend_record(copy, {key: f"{float(meta[key]) + sign * DIAMETER_RESOLUTION_MM:.4f}"})
                out.append(row(copy))
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--records", type=Path, default=ROOT / "tests" / "fe" / "data")
    ap.add_argument("--no-resolution", action="store_true", help="skip the readings-off-by-one-step table")
    args = ap.parse_args(argv)
    rows = [row(p) for p in records(args.records)]
    print("record              | μ face ± se     μ bulge ± se    |    z      s      r    | truth: mean (centre/rim) | μ ± U            |Δ|/U held | W Z")
    for r in rows:
        truth = f"{r['truth']:.3f} ({r['center']:.3f}/{r['rim']:.3f})" if r["zoned"] else f"{r['truth']:.3f}              "
        print(f"{r['name']:19s} | {r['face']:.3f} ± {r['se_f']:.3f}  {r['bulge']:.3f} ± {r['se_b']:.3f}  | {r['z']:5.2f} {r['s']:+6.2f} {r['r']:+6.2f} | "
              f"{truth:24s} | {r['mu']:.3f} ± {r['U']:.3f}  {r['zU']:5.2f} {'yes' if r['zU'] <= 1 else 'NO ':3s}  | "
              f"{'W' if r['W'] else '-'} {'Z' if r['Z'] else '-'}")
    groups = (("uniform", [r for r in rows if not r["zoned"]]), ("zoned, lubricated centre", [r for r in rows if r["zoned"] and not r["dry"]]),
              ("zoned, dry centre", [r for r in rows if r["dry"]]))
    print()
    for name, g in groups:
        if g:
            print(f"{name:25s} ({len(g):2d}): s {min(r['s'] for r in g):+.2f} … {max(r['s'] for r in g):+.2f}, "
                  f"r {min(r['r'] for r in g):+.2f} … {max(r['r'] for r in g):+.2f}, z {min(r['z'] for r in g):.2f} … {max(r['z'] for r in g):.2f}; "
                  f"μ ± U holds the truth on {sum(r['zU'] <= 1 for r in g)}")
    if args.no_resolution:
        return 0
    print(f"\ndface or dmax off by ±{DIAMETER_RESOLUTION_MM} mm: each record's s, r and t as read | least … largest over the four readings")
    spans = {}
    for p, r in zip(records(args.records), rows):
        off = off_by_resolution(p)
        spans[r["name"]] = {k: (min(o[k] for o in off), max(o[k] for o in off)) for k in ("s", "r", "t")}
        print(f"{r['name']:19s} | s {r['s']:+6.2f} ({spans[r['name']]['s'][0]:+6.2f} … {spans[r['name']]['s'][1]:+6.2f})  "
              f"r {r['r']:+6.2f} ({spans[r['name']]['r'][0]:+6.2f} … {spans[r['name']]['r'][1]:+6.2f})  "
              f"t {r['t']:+6.2f} ({spans[r['name']]['t'][0]:+6.2f} … {spans[r['name']]['t'][1]:+6.2f})")
    print()
    for k in ("s", "r", "t"):
        top = max(spans[r["name"]][k][1] for r in rows if not r["dry"])
        low = min(spans[r["name"]][k][0] for r in rows if r["dry"])
        top0 = max(r[k] for r in rows if not r["dry"])
        low0 = min(r[k] for r in rows if r["dry"])
        print(f"{k}: as read, largest not-dry {top0:+.2f} against least dry {low0:+.2f}; one step off, {top:+.2f} against {low:+.2f} "
              + ("(separated)" if low > top else "(overlap)"))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
