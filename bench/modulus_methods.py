"""The elastic line by SDAR (ASTM E3076-18) against the automatic window, on every record with a
known modulus: which one lands closer more often, and which refuses less.

Records (none made by the code under test):
* the 67 published 42CrMoS4 specimens (extensometer; the lab's slope of the linear-elastic region);
* closed-form crosshead-only tension records: a Voce steel with Ag ≈ 1 %, the frame compliance
  (10.8, 40 and 136 N/µm) and a seating toe that closes at 10–50 % of Fm, at constant crosshead
  speed, 10 Hz, force noise and 1 µm steps — known: the apparent modulus of specimen and frame in
  series, 1/E_app = 1/E + S0/(L0·C), and the Rp0.2 on the crosshead curve with that slope (the
  offset line from the straight part's zero, intersected with the noiseless curve);
* virtual-rig records (the physical model behind the virtual devices, on model time) of three
  materials, tension and compression, their material.E_MPa dropped — known: that E;
* with --calculix: CalculiX upsetting records (:func:`identification.fe.synthetic.upsetting_record`)
  of the seed law at μ 0.15 with toes of 0, 0.02 and 0.05 mm at 10 Hz, material.E_MPa dropped —
  known: the model's E (one ccx run, ~1 min).

"auto" is the default that came of it: SDAR on crosshead-only tension records, the window else.
Closer: |E/E_known − 1| smaller, counted where both methods answered. A refusal is a one-line
error instead of a modulus; an answer more than 5 % off is counted apart (a confident wrong one).

Run: python bench/modulus_methods.py [--calculix]   (~1 min without CalculiX)
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd

from flowcurve.errors import FlowcurveError
from flowcurve.record.format import Record

METHODS = ("window", "sdar", "auto")  # auto: the default (SDAR on a crosshead-only tension record, else the window)
DATA = Path(__file__).resolve().parents[1] / "tests" / "data" / "42CrMoS4" / "original_data"  # vendored, CC BY 4.0
D0_MM, L0_MM = 6.0, 30.0


def crosshead_tension(*, sy=850.0, Q=150.0, b=300.0, E=205_000.0, frame_N_per_um=10.8, toe_mm=0.05, toe_fraction=0.1,
                      rate_hz=10.0, speed_mm_per_s=0.02, noise=0.0005, quantum_mm=0.001, seed=0) -> tuple[Record, float, float]:
    """(record, known apparent modulus MPa, Rp0.2 MPa with that slope) of a crosshead-only tension
    test: Voce σ = sy + Q(1 − e^(−bεp)) (Ag ≈ 1 % with the defaults), constant volume, a neck after
    Fm; crosshead = specimen + P/C + seat(P), seat = toe·(1 − (1 − P/P_toe)²) below P_toe."""
    s0 = math.pi * D0_MM**2 / 4.0
    ep = np.concatenate([[0.0], np.geomspace(1e-7, 0.2, 4000)])
    s_el = np.linspace(0.0, sy, 400, endpoint=False)
    sig = np.concatenate([s_el, sy + Q * (1.0 - np.exp(-b * ep))])
    eps_p = np.concatenate([np.zeros_like(s_el), ep])
    e = np.expm1(eps_p + sig / E)
    s = sig / (1.0 + e)
    i_m = int(np.argmax(s))
    s, e = s[: i_m + 1], e[: i_m + 1]
    s = np.concatenate([s, s[-1] * np.linspace(1.0, 0.7, 40)[1:]])  # the neck: the force falls 30 % over 3 % strain
    e = np.concatenate([e, e[-1] + np.linspace(0.0, 0.03, 40)[1:]])
    force = s * s0
    seat = toe_mm * (1.0 - np.clip(1.0 - force / (toe_fraction * force.max()), 0.0, 1.0) ** 2)
    cross = e * L0_MM + force / (frame_N_per_um * 1000.0) + seat
    t = np.arange(0.0, cross[-1] / speed_mm_per_s, 1.0 / rate_hz)
    rng = np.random.default_rng(seed)
    f_t = np.interp(t * speed_mm_per_s, cross, force) + rng.normal(0.0, noise * force.max(), t.size)
    c_t = np.round(t * speed_mm_per_s / quantum_mm) * quantum_mm
    E_app = 1.0 / (1.0 / E + s0 / (L0_MM * frame_N_per_um * 1000.0))  # specimen and frame in series, on the crosshead strain
    # Rp0.2 with the slope of the straight part: its line meets zero force at e0 = toe/L0 (the seat closed)
    strain = cross / L0_MM
    g = s[: i_m + 1] - E_app * (strain[: i_m + 1] - toe_mm / L0_MM - 0.002)
    k = int(np.argmax((g <= 0) & (s[: i_m + 1] > 0.5 * s[i_m])))
    rp02 = float(s[k - 1] + g[k - 1] / (g[k - 1] - g[k]) * (s[k] - s[k - 1]))
    meta = {"test": "tension", "specimen.d0_mm": repr(D0_MM), "specimen.l0_mm": repr(L0_MM), "crosshead_speed_mm_per_s": repr(speed_mm_per_s),
            "specimen.parallel_length_mm": repr(L0_MM), "material": "Voce steel (closed form)"}  # the crosshead stretches L0: Lc = L0
    return Record(meta=meta, data=pd.DataFrame({"time_s": t, "force_N": f_t, "crosshead_mm": c_t}),
                  source=f"crosshead C{frame_N_per_um:g} toe{toe_mm:g}@{toe_fraction:g}Fm"), E_app, rp02


CROSSHEAD_CASES = [dict(frame_N_per_um=c, toe_mm=toe, toe_fraction=frac, seed=i)
                   for i, (c, toe, frac) in enumerate((c, toe, frac) for c in (10.8, 40.0, 136.0) for toe in (0.0, 0.05, 0.2)
                                                      for frac in (0.1, 0.3, 0.5))]


def published_records():
    from flowcurve.record.importers import load_record

    for path in sorted(DATA.glob("*.csv")):
        rec = load_record(path)
        yield "42CrMoS4", path.stem, rec, rec.number("published.E_MPa", required=True)


def crosshead_records():
    for case in CROSSHEAD_CASES:
        rec, E_app, _ = crosshead_tension(**case)
        yield "crosshead (closed form)", rec.source, rec, E_app


def virtual_records():
    from flowcurve.acquisition.session import run_virtual_test
    from flowcurve.clock import ModelClock
    from flowcurve.demo import demo_specs
    from flowcurve.record.format import read_record

    folder = Path(tempfile.mkdtemp(prefix="flowcurve-modulus-"))
    for material in ("steel45", "12Kh18N10T", "12Kh18N12M3TL"):
        for spec in demo_specs(material):
            path = folder / f"{material}-{spec.test}.csv"
            run_virtual_test(spec, path, material=material, time_scale=15.0, clock=ModelClock(), link="inprocess")
            rec = read_record(path)
            known = float(rec.meta.pop("material.E_MPa"))
            yield "virtual rig", f"{material} {spec.test}", rec, known


def calculix_records():
    from flowcurve.identification.fe import synthetic as syn

    case = {"name": "seed law, mu 0.15", "law": (syn.johnson_cook_flow, {"A": 105.0, "B": 1392.0, "n": 0.642}), "mu": 0.15,
            "d0": 6.0, "h0": 9.0, "eps_end": 0.72, "E": 194_000.0}
    run = syn.run_case(case)
    for toe in (0.0, 0.02, 0.05):
        rec = syn.upsetting_record(run, toe_mm=toe, rate_hz=10.0, specimen_id=f"ccx toe {toe:g}")
        known = float(rec.meta.pop("material.E_MPa"))
        yield "CalculiX upsetting", f"mu 0.15 toe {toe:g} mm 10 Hz", rec, known


def moduli(rec: Record) -> dict[str, float | str]:
    """E by each method (MPa), or the refusal's message: tension up to its elastic line (the ISO
    results after it are not what is compared), compression through the identification."""
    from flowcurve.identification.tension.elastic import _elastic_line
    from flowcurve.identification.tension.inputs import _inputs
    from flowcurve.identification.compression.identify import identify_compression

    out: dict[str, float | str] = {}
    for method in METHODS:
        try:
            if rec.test == "compression":
                res = identify_compression(rec, modulus_method=method).result
                E = (res.get("modulus") or {}).get("E_line_MPa")
            else:
                inp = _inputs(rec, use_extensometer=None, frame_stiffness_N_per_um=None, crosshead_length_mm=None, scale=True)
                E = _elastic_line(inp, fractions=None, window_fixed_MPa=None, modulus_reference="Rp02", E_MPa=None, toe=True,
                                  scale=True, modulus_method=method).E
            out[method] = float(E) if E is not None else "no modulus"
        except FlowcurveError as exc:
            out[method] = str(exc).splitlines()[0]
    return out


def compare(groups) -> list[dict]:
    rows = []
    for group, name, rec, known in groups:
        got = moduli(rec)
        row = {"group": group, "record": name, "known_MPa": known}
        for method in METHODS:
            v = got[method]
            row[method] = (v / known - 1.0) if isinstance(v, float) else None
            row[f"{method}_refusal"] = None if isinstance(v, float) else v
        rows.append(row)
    return rows


FAR_OFF = 0.05  # a modulus further than this from the known one is a wrong answer, worse than a refusal


def tally(rows: list[dict]) -> dict[str, dict[str, int]]:
    """Per group and in all: records; where both methods answered, which is closer (a tie within
    0.01 % to neither); refusals; answers more than 5 % off (confident wrong answers)."""
    out: dict[str, dict[str, int]] = {}
    for key in sorted({r["group"] for r in rows}) + ["all"]:
        sel = [r for r in rows if key == "all" or r["group"] == key]
        t = {"records": len(sel), "window_closer": 0, "sdar_closer": 0, "ties": 0}
        for r in sel:
            w, s = r["window"], r["sdar"]
            if w is None or s is None:
                continue
            if abs(w) < abs(s) - 1e-4:
                t["window_closer"] += 1
            elif abs(s) < abs(w) - 1e-4:
                t["sdar_closer"] += 1
            else:
                t["ties"] += 1
        for m in METHODS:
            dev = np.array([abs(r[m]) for r in sel if r[m] is not None])
            t[f"{m}_refusals"] = sum(r[m] is None for r in sel)
            t[f"{m}_far_off"] = int(np.sum(dev > FAR_OFF))
            t[f"{m}_median_pct"] = float(100 * np.median(dev)) if dev.size else float("nan")
            t[f"{m}_within_2pct"] = int(np.sum(dev <= 0.02))
        out[key] = t
    return out


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--calculix", action="store_true", help="add the CalculiX upsetting records (one ccx run)")
    p.add_argument("--verbose", action="store_true", help="one line per record")
    args = p.parse_args(argv)
    sources = [crosshead_records(), virtual_records()]
    if DATA.exists():
        sources.insert(0, published_records())
    else:
        print(f"(no 42CrMoS4 data in {DATA})", file=sys.stderr)
    if args.calculix:
        sources.append(calculix_records())
    t0 = time.perf_counter()
    rows = [r for src in sources for r in compare(src)]
    if args.verbose:
        for r in rows:
            cells = [f"{m} " + (f"{100 * r[m]:+8.2f} %" if r[m] is not None else f"refused: {r[m + '_refusal'][:50]}") for m in METHODS]
            print(f"{r['group']:<24}{r['record']:<30}{r['known_MPa']:>10.0f}  " + "  ".join(cells))
    print(f"\n{'records':<24}{'n':>4}{'window closer':>15}{'sdar closer':>13}{'ties':>6}{'refused w/s/a':>16}{'>5 % off w/s/a':>16}"
          f"{'median |dev| % w/s/a':>24}{'≤2 % w/s/a':>13}")
    for key, t in tally(rows).items():
        per = lambda k, f="{}": "/".join(f.format(t[f"{m}_{k}"]) for m in METHODS)  # noqa: E731
        print(f"{key:<24}{t['records']:>4}{t['window_closer']:>15}{t['sdar_closer']:>13}{t['ties']:>6}{per('refusals'):>16}{per('far_off'):>16}"
              f"{per('median_pct', '{:.2f}'):>24}{per('within_2pct'):>13}")
    print(f"\n{time.perf_counter() - t0:.0f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
