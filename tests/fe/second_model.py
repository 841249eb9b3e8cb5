"""A second upsetting model, built apart from the product's (identification/fe/model/upsetting.py), to
make compression records the product's FE table and inverse have never seen (issue 37).

It shares nothing with the product's model but CalculiX itself: its own deck, mesh, contact,
increments and output parsing. Where the product uses an O-grid core with a diagonal rim
layer, surface-to-surface contact with stick slope 1e7 N/mm³ and 50 increments, this one uses

* a structured mesh of CAX4R elements graded geometrically toward the free surface and toward
  the platen (the smallest element at the rim corner, :data:`GRADING` of its neighbour's size);
* node-to-surface penalty contact (slope 1e8 N/mm³) with Coulomb friction and a stick slope of
  1e5 N/mm³ (the held-out records' setting of issue 37);
* the platen driven in 200 equal increments; hk, dmax and dface are read off the loaded mesh (the
  top axis node, the widest side node, the original rim-corner node) and sprung back elastically
  (h·(1 + σ/E), d·(1 − ν·σ/E), σ = F/A). A lift in 30 increments was tried and fails at its first
  increment ("too many cutbacks", friction reversing, with stick slope 1e5 or 1e7 and with a
  small tension cut-off σ∞), as docs/calculix.md reports for the product's model; the record's
  unloading branch is therefore the elastic one, F → 0 with the stroke back by h·σ/E.

:func:`write_record` adds the rig: frame compliance 136 N/µm, a seating toe
0.02·(1 − e^(−F/100 N)) mm, 15 N force noise, 1 µm crosshead counts, 10 Hz sampling.

Use: ``run = simulate(Case(...)); write_record(run, path)``. The deck runs in a temporary folder
with ``ccx`` on the PATH (one thread).
"""

from __future__ import annotations

import math
import os
import re
import subprocess
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from flowcurve.record.format import RecordWriter

GRADING = 0.88  # each element this fraction of its inner (lower) neighbour's size toward the rim (the platen)
PENALTY_N_PER_MM3 = 1e8
STICK_SLOPE_N_PER_MM3 = 1e5
LOAD_INCREMENTS = 200
UNLOAD_S = 20.0  # the record's elastic unloading branch takes this long
SECTOR = 180.0  # CAX reaction forces are for a 2° sector: × 180 for the ring


@dataclass(frozen=True)
class Case:
    """A specimen, its material (Johnson–Cook-like σ = A + B·εp^n, E) and the friction."""

    name: str
    A_MPa: float
    B_MPa: float
    n: float
    E_MPa: float
    mu: float
    d0_mm: float
    h0_mm: float
    h_end_mm: float
    nu: float = 0.3
    nr: int = 10  # radial elements (CAX8R 8 → 12: dmax within 1 µm, dface 0.09 mm apart at C3)
    element: str = "CAX8R"

    def flow(self, eps_p):
        return self.A_MPa + self.B_MPa * np.asarray(eps_p, float) ** self.n


@dataclass
class SecondRun:
    """The simulated loading (per increment) and the unloaded shape."""

    case: Case
    stroke_mm: np.ndarray  # specimen shortening (both ends)
    force_N: np.ndarray  # compressive force, positive
    height_mm: float  # loaded final height
    hk_mm: float
    dmax_mm: float
    dface_mm: float
    solver_s: float


def _graded(length: float, n: int, ratio: float) -> np.ndarray:
    """n+1 coordinates on [0, length], element sizes a geometric series with ``ratio`` (finer at the end)."""
    sizes = ratio ** np.arange(n)
    return np.concatenate([[0.0], np.cumsum(sizes) / sizes.sum() * length])


def contact_zones(case: Case, r: np.ndarray, top: list, side: list) -> list[tuple[str, list, float]]:
    """The slave node sets and their μ: (name suffix, node ids, μ). One zone, the end face and the side, at
    ``case.mu``; a case with a ``zones`` method (tests/fe/zoned_friction.py) splits it."""
    if hasattr(case, "zones"):
        return case.zones(r, top, side)
    return [("", sorted(set(top[1:] + side)), case.mu)]  # the axis node is driven with the platen (no master face reaches r = 0)


def _deck(case: Case) -> tuple[str, dict]:
    R, H = case.d0_mm / 2.0, case.h0_mm / 2.0  # half model: symmetry at mid-height
    nz = max(6, int(round(case.nr * H / R)))
    r, z = _graded(R, case.nr, GRADING), _graded(H, nz, GRADING)
    k = 2 if case.element == "CAX8R" else 1  # grid points per element edge
    if k == 2:  # the mid-side nodes halfway
        r = np.insert(r, np.arange(1, r.size), (r[1:] + r[:-1]) / 2.0)
        z = np.insert(z, np.arange(1, z.size), (z[1:] + z[:-1]) / 2.0)
    ncol = r.size
    lines = ["*HEADING", f"second upsetting model {case.name}", "*NODE"]
    nid = lambda i, j: 1 + j * ncol + i  # noqa: E731  grid node (i radial, j axial)
    for j, zj in enumerate(z):
        for i, ri in enumerate(r):
            if not (k == 2 and i % 2 and j % 2):  # no centre nodes (CAX8R has none)
                lines.append(f"{nid(i, j)}, {ri:.9g}, {zj:.9g}, 0")
    top = [nid(i, z.size - 1) for i in range(ncol)]
    side = [nid(ncol - 1, j) for j in range(z.size)]
    zones = contact_zones(case, r, top, side)  # [(suffix, slave nodes, μ)]: one zone unless the case splits its face
    # the platen: one row of elements over 0..2.2 R, its lower face at the specimen's top; a copy of it (the same
    # driven nodes' places) for each further zone: two contact pairs on one master face lost a slave node in ccx 2.20
    n_spec = ncol * z.size
    pr = np.linspace(0.0, 2.2 * R, 23)
    pid = lambda i, j, q=0: n_spec + 1 + q * 2 * len(pr) + j * len(pr) + i  # noqa: E731
    for q in range(len(zones)):
        for j, zj in enumerate((H, H + 0.5)):
            for i, ri in enumerate(pr):
                lines.append(f"{pid(i, j, q)}, {ri:.9g}, {zj:.9g}, 0")
    lines.append(f"*ELEMENT, TYPE={case.element}, ELSET=SPECIMEN")
    eid = 0
    for j in range(0, z.size - 1, k):
        for i in range(0, ncol - 1, k):
            eid += 1
            corners = [nid(i, j), nid(i + k, j), nid(i + k, j + k), nid(i, j + k)]
            mids = [nid(i + 1, j), nid(i + 2, j + 1), nid(i + 1, j + 2), nid(i, j + 1)] if k == 2 else []
            lines.append(f"{eid}, " + ", ".join(map(str, corners + mids)))
    platen_elems = [[] for _ in zones]
    for q in range(len(zones)):
        lines.append("*ELEMENT, TYPE=CAX4R, ELSET=PLATEN")
        for i in range(len(pr) - 1):
            eid += 1
            platen_elems[q].append(eid)
            lines.append(f"{eid}, {pid(i, 0, q)}, {pid(i + 1, 0, q)}, {pid(i + 1, 1, q)}, {pid(i, 1, q)}")
    masters = [""] + [suffix for suffix, _, _ in zones[1:]]  # MASTER, then MASTER<suffix> on each copy

    def nset(name, ids):
        ids = list(ids)
        return [f"*NSET, NSET={name}"] + [", ".join(map(str, ids[k:k + 12])) for k in range(0, len(ids), 12)]

    lines += nset("AXIS", [nid(0, j) for j in range(z.size)])
    lines += nset("MID", [nid(i, 0) for i in range(ncol)])
    for suffix, ids, _ in zones:
        lines += nset(f"CONTACT{suffix}", ids)
    lines += nset("PLATEN", [pid(i, j, q) for q in range(len(zones)) for j in range(2) for i in range(len(pr))])
    lines += nset("TOPAXIS", [top[0]])
    lines += nset("SHAPE", sorted(set(top + side)))
    for m, elems in zip(masters, platen_elems):
        lines += [f"*ELSET, ELSET=PLATENFACE{m}"] + [", ".join(map(str, elems[k:k + 12])) for k in range(0, len(elems), 12)]
    for suffix, _, _ in zones:
        lines += [f"*SURFACE, NAME=SLAVE{suffix}, TYPE=NODE", f"CONTACT{suffix}"]
    for m in masters:
        lines += [f"*SURFACE, NAME=MASTER{m}", f"PLATENFACE{m}, S1"]
    eps = np.concatenate([[0.0], np.geomspace(1e-4, 3.0, 70)])
    lines += ["*MATERIAL, NAME=METAL", "*ELASTIC", f"{case.E_MPa:.9g}, {case.nu}", "*PLASTIC"]
    lines += [f"{s:.9g}, {e:.9g}" for e, s in zip(eps, case.flow(eps))]
    lines += ["*MATERIAL, NAME=RIGID", "*ELASTIC", "2.1e6, 0.3",
              "*SOLID SECTION, ELSET=SPECIMEN, MATERIAL=METAL", "*SOLID SECTION, ELSET=PLATEN, MATERIAL=RIGID"]
    for suffix, _, mu in zones:  # each zone its own Coulomb μ
        lines += [f"*SURFACE INTERACTION, NAME=SI{suffix}", "*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR", f"{PENALTY_N_PER_MM3:.6g}"]
        if mu > 0:
            lines += ["*FRICTION", f"{mu}, {STICK_SLOPE_N_PER_MM3:.6g}"]
    for (suffix, _, _), m in zip(zones, masters):
        lines += [f"*CONTACT PAIR, INTERACTION=SI{suffix}, TYPE=NODE TO SURFACE", f"SLAVE{suffix}, MASTER{m}"]
    lines += ["*BOUNDARY", "AXIS, 1, 1", "MID, 2, 2", "PLATEN, 1, 1"]
    half_stroke = (case.h0_mm - case.h_end_mm) / 2.0
    step = lambda inc, y: ["*STEP, NLGEOM, INC=2000", "*STATIC", f"{1.0 / inc:.9g}, 1.0, 1e-7, {1.0 / inc:.9g}",  # noqa: E731
                           "*BOUNDARY", f"PLATEN, 2, 2, {y:.9g}", f"TOPAXIS, 2, 2, {y:.9g}",
                           "*NODE PRINT, NSET=PLATEN, TOTALS=ONLY", "RF", "*NODE PRINT, NSET=TOPAXIS", "U",
                           "*NODE FILE, NSET=SHAPE", "U", "*END STEP"]
    lines += step(LOAD_INCREMENTS, -half_stroke)
    geometry = {"r": r, "z": z, "ncol": ncol, "top": top, "side": side, "rim": top[-1]}
    return "\n".join(lines) + "\n", geometry


_FLOAT = r"[-+]?\d*\.?\d+(?:[eE][-+]?\d+)?"


def _dat_series(dat: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(time, platen force sum y, top-axis node uy) per increment from the .dat (time runs 0–2 over both steps)."""
    forces = re.findall(rf"total force \(fx,fy,fz\) for set PLATEN and time\s+({_FLOAT})\s*\n\s*({_FLOAT})\s+({_FLOAT})", dat)
    disp = re.findall(rf"displacements \(vx,vy,vz\) for set TOPAXIS and time\s+({_FLOAT})\s*\n\s*\d+\s+({_FLOAT})\s+({_FLOAT})", dat)
    t = np.array([float(a) for a, _, _ in forces])
    fy = np.array([float(c) for _, _, c in forces])
    uy = np.array([float(c) for _, _, c in disp])
    return t, fy, uy


def _frd_displacements_at_end(frd: str) -> dict[int, tuple[float, float]]:
    """The node displacements (ux, uy) of the .frd's result block at step time 1 (a failed run
    appends a block of its last, unconverged iteration: skipped)."""
    chosen = None
    for block in frd.split("  100CL")[1:]:
        head = block.split()
        if float(head[1]) <= 1.0 + 1e-9 and " -4  DISP" in block:
            chosen = block[block.index(" -4  DISP"):]
    if chosen is None:
        raise RuntimeError("no displacement block at the end of the loading in the .frd")
    out: dict[int, tuple[float, float]] = {}
    for line in chosen.splitlines():
        if line.startswith(" -1"):
            body = line[3:]
            node = int(body[:10])
            vals = [float(body[10 + 12 * k:22 + 12 * k]) for k in range(2)]
            out[node] = (vals[0], vals[1])
        elif line.startswith(" -3"):
            break
    return out


def simulate(case: Case, workdir: Path | None = None) -> SecondRun:
    """Run the deck with ccx (one thread); raise RuntimeError when the loading step does not finish."""
    deck, geo = _deck(case)
    with tempfile.TemporaryDirectory(prefix="fe2-") as tmp:
        job = Path(workdir or tmp)
        job.mkdir(parents=True, exist_ok=True)
        (job / "up.inp").write_text(deck)
        t0 = time.perf_counter()
        proc = subprocess.run(["ccx", "-i", "up"], cwd=job, capture_output=True, text=True,
                              env={**os.environ, "OMP_NUM_THREADS": "1"}, timeout=3600)
        solver_s = time.perf_counter() - t0
        dat = (job / "up.dat").read_text() if (job / "up.dat").exists() else ""
        frd = (job / "up.frd").read_text() if (job / "up.frd").exists() else ""
    t, fy, uy = _dat_series(dat)
    if t.size == 0 or np.max(t) < 1.0 - 1e-6:
        tail = "\n".join(proc.stdout.splitlines()[-5:])
        raise RuntimeError(f"{case.name}: the loading stopped at time {np.max(t, initial=0.0):.3f}: {tail}")
    force = -fy * SECTOR  # the platen pushes down: a negative reaction
    stroke = -2.0 * uy  # the top-axis node's travel, both halves
    u = _frd_displacements_at_end(frd)
    xy = {n: (geo["r"][(n - 1) % geo["ncol"]] + u[n][0], geo["z"][(n - 1) // geo["ncol"]] + u[n][1]) for n in u}
    h = 2.0 * xy[geo["top"][0]][1]
    sigma = force[-1] / (math.pi * case.d0_mm**2 * case.h0_mm / (4.0 * h))  # mean axial stress at the end
    spring = 1.0 - case.nu * sigma / case.E_MPa
    return SecondRun(case=case, stroke_mm=stroke, force_N=force, height_mm=h, hk_mm=h * (1.0 + sigma / case.E_MPa),
                     dmax_mm=2.0 * max(xy[n][0] for n in geo["side"]) * spring, dface_mm=2.0 * xy[geo["rim"]][0] * spring,
                     solver_s=solver_s)


def write_record(run: SecondRun, path: Path, *, stiffness_N_per_um: float = 136.0, toe_mm: float = 0.02, toe_force_N: float = 100.0,
                 noise_N: float = 15.0, step_mm: float = 0.001, rate_hz: float = 10.0, speed_mm_per_s: float = 0.02, seed: int = 1,
                 end_face: bool = True) -> Path:
    """The record the rig would have written: crosshead = specimen + toe(F) + F/C at constant speed,
    sampled at ``rate_hz``, 1 µm counts, force noise; compression negative. Post: hk, dmax (and dface)."""
    c = run.case
    rng = np.random.default_rng(seed)
    compliance = 1.0 / (stiffness_N_per_um * 1000.0)  # mm/N
    # the elastic line up to yield, F = E·A0·s/h0 (the first of 200 increments is already plastic)
    s_yield = c.A_MPa * c.h0_mm / c.E_MPa
    first = [s_yield, c.A_MPa * math.pi * c.d0_mm**2 / 4.0] if s_yield < run.stroke_mm[0] else []
    s = np.concatenate([[0.0], first[:1], run.stroke_mm])
    f = np.concatenate([[0.0], first[1:], run.force_N])
    toe = lambda F: toe_mm * -np.expm1(-F / toe_force_N)  # noqa: E731  the seating toe, in series
    # loading: the crosshead at constant speed; each sample's specimen stroke from crosshead = s + toe(F) + F/C
    cross = np.maximum.accumulate(s + toe(f) + f * compliance)
    t_load = np.arange(0.0, cross[-1] / speed_mm_per_s, 1.0 / rate_hz)
    s_load = np.interp(t_load * speed_mm_per_s, cross, s)
    f_load = np.interp(s_load, s, f)
    # unloading: F → 0 in UNLOAD_S, the specimen springs back by h·σ/E (linear in F), the toe stays closed
    frac = 1.0 - np.arange(1, int(UNLOAD_S * rate_hz) + 1) / (UNLOAD_S * rate_hz)
    sigma = run.force_N[-1] / (math.pi * c.d0_mm**2 * c.h0_mm / (4.0 * run.height_mm))
    f_un = run.force_N[-1] * frac
    s_un = s[-1] - run.height_mm * sigma / c.E_MPa * (1.0 - frac)
    F = np.concatenate([f_load, f_un])
    x = np.concatenate([s_load + toe(f_load), s_un + toe(run.force_N[-1])]) + F * compliance
    rows = np.column_stack([np.arange(F.size) / rate_hz, F, x])
    force = rows[:, 1] + rng.normal(0.0, noise_N, len(rows))
    crosshead = np.round(rows[:, 2] / step_mm) * step_mm
    meta = {
        "test": "compression", "material": f"second FE model {c.name}", "specimen.id": c.name, "nominal_temperature_C": "20",
        "crosshead_speed_mm_per_s": repr(speed_mm_per_s), "rig.frame_stiffness_N_per_um": repr(stiffness_N_per_um),
        "specimen.d0_mm": repr(c.d0_mm), "specimen.h0_mm": repr(c.h0_mm), "material.E_MPa": repr(c.E_MPa),
        "post.hk_mm": f"{run.hk_mm:.4f}", "post.dmax_mm": f"{run.dmax_mm:.4f}",
        # the truth it was made with (not read by identification)
        "fe2.mu": repr(c.mu), "fe2.A_MPa": repr(c.A_MPa), "fe2.B_MPa": repr(c.B_MPa), "fe2.n": repr(c.n),
        "fe2.unloading": "elastic (h·σ/E)",
    }
    if end_face:
        meta["post.dface_mm"] = f"{run.dface_mm:.4f}"
    with RecordWriter(path, meta, ["time_s", "force_N", "crosshead_mm"], float_format="%.4f") as rec:
        rec.append_rows(np.column_stack([rows[:, 0], -force, -crosshead]))
    return Path(path)


C2 = Case("C2", A_MPa=280.0, B_MPa=1215.0, n=0.43, E_MPa=180_000.0, mu=0.05, d0_mm=6.0, h0_mm=9.0, h_end_mm=4.5)
C3 = Case("C3", A_MPa=410.0, B_MPa=280.0, n=0.47, E_MPa=200_000.0, mu=0.2, d0_mm=6.0, h0_mm=6.0, h_end_mm=3.6)
# the held-out records over h0/d0 1.0–2.0 and μ 0.05–0.3 (issue 37); S3 to h 5.6 mm: to 4.8 mm its side folded at 0.916 of the stroke
HELD_OUT = (
    Case("C1", 105.0, 1392.0, 0.642, 194_000.0, 0.15, 6.0, 9.0, 4.5),
    C2,
    C3,
    Case("S1", 300.0, 600.0, 0.30, 200_000.0, 0.05, 6.0, 6.0, 3.6),
    Case("S2", 250.0, 900.0, 0.50, 200_000.0, 0.30, 6.0, 7.2, 3.6),
    Case("S3", 350.0, 500.0, 0.25, 210_000.0, 0.10, 6.0, 9.6, 5.6),
    Case("S4", 200.0, 700.0, 0.40, 200_000.0, 0.20, 5.0, 10.0, 5.0),
    Case("S5", 400.0, 400.0, 0.35, 200_000.0, 0.30, 5.0, 10.0, 5.0),
    Case("S6", 150.0, 1000.0, 0.55, 195_000.0, 0.25, 5.0, 9.0, 4.5),
)


def curve_error(true_curve, case: Case, lo: float = 0.05, hi: float = 0.6) -> float:
    """The largest |σ/σ_true − 1| of an identified true curve (true_plastic_strain, true_stress_MPa) over ε_p lo–hi
    (within the curve's reach)."""
    e, s = (np.asarray(true_curve[k], float) for k in ("true_plastic_strain", "true_stress_MPa"))
    sel = (e >= lo) & (e <= hi)
    return float(np.max(np.abs(s[sel] / case.flow(e[sel]) - 1.0)))


def identify_default(path: Path, out: Path, *, end_face: bool) -> tuple[dict, float]:
    """``flowcurve identify`` (its defaults) on the record, with or without its post.dface_mm: (result.json, curve error)."""
    import json
    import shutil

    import pandas as pd

    from flowcurve.cli import main as cli_main
    from flowcurve.record.format import amend_record, read_record

    out.mkdir(parents=True, exist_ok=True)
    copy = out / Path(path).name
    shutil.copyfile(path, copy)
    if not end_face:
        amend_record(copy, {"post.dface_mm": None})
    meta = read_record(copy).meta
    case = Case(meta["specimen.id"], *(float(meta[f"fe2.{k}"]) for k in ("A_MPa", "B_MPa", "n")), float(meta["material.E_MPa"]),
                float(meta["fe2.mu"]), float(meta["specimen.d0_mm"]), float(meta["specimen.h0_mm"]), float(meta["post.hk_mm"]))
    if cli_main(["identify", str(copy), "--out", str(out), "--no-plots"]) != 0:
        raise RuntimeError(f"flowcurve identify failed on {copy}")
    folder = out / copy.stem
    result = json.loads((folder / "result.json").read_text())
    return result, curve_error(pd.read_csv(folder / "true_curve.csv", comment="#"), case)


def coverage_row(path: Path, out: Path, *, end_face: bool) -> dict:
    """The default's μ on a record against its truth (header ``fe2.mu``) in the result's own
    standard errors (``friction_details.fe_table.mu_stderr``): record, truth μ, μ, se,
    z = |μ − truth|/se, the curve error and the hardening's quality."""
    from flowcurve.record.format import read_record

    result, err = identify_default(path, out, end_face=end_face)
    meta = read_record(path).meta
    truth, mu = float(meta["fe2.mu"]), float(result["friction_mu"])
    se = float(result["friction_details"]["fe_table"]["mu_stderr"])
    return {"record": meta["specimen.id"], "h0_d0": float(meta["specimen.h0_mm"]) / float(meta["specimen.d0_mm"]), "truth_mu": truth,
            "mu": mu, "se": se, "z": abs(mu - truth) / se if se > 0 else math.inf, "curve_error": err,
            "quality": result["hardening"]["quality"]}


def assert_regenerated(made: Path, vendored: Path) -> None:
    """A record made again matches the vendored one: post-test shape to 0.2 µm, the same rows, forces to 0.5 N."""
    from flowcurve.record.format import read_record

    new, old = read_record(made), read_record(vendored)
    for key in ("post.hk_mm", "post.dmax_mm", "post.dface_mm"):
        assert abs(float(new.meta[key]) - float(old.meta[key])) <= 2e-4, key
    assert len(new.data) == len(old.data)
    assert (new.data["force_N"] - old.data["force_N"]).abs().max() < 0.5
