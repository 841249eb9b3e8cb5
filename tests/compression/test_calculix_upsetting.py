"""CalculiX upsetting runs as an independent check of the friction corrections.

Half model (symmetry at mid-height) of a d0 = 6, h0 = 7 mm cylinder compressed to 4.2 mm,
CAX4R 12×14, a meshed carbide platen whose nodes are all driven, surface-to-surface contact
with Coulomb friction μ (CALCULIX.md, "Upsetting"). A plain rectangular mesh is enough for
μ ≤ 0.1 (it fails near μ = 0.3, where CALCULIX.md prescribes the O-grid mesh).

Two runs, μ = 0 and μ = 0.1 (~2 s each, side by side). The μ = 0 run measures the mesh's own
force deficit (p/σ_f below 1); the μ = 0.1 run divided by it is the friction factor p/σ_f
that the slab and Siebel corrections claim to remove.
"""

from __future__ import annotations

import math
import os
import re
import shutil
import subprocess

import numpy as np
import pytest

from flowcurve.identification import friction as fr

pytestmark = [pytest.mark.slow, pytest.mark.solver,
              pytest.mark.skipif(shutil.which("ccx") is None, reason="CalculiX (ccx) is not installed")]

R0, H, DZ, E = 3.0, 3.5, 1.4, 194_000.0  # half model: radius, half height, platen travel (mm), MPa
SECTOR = 180.0  # CAX reaction totals are for a 2° sector


def flow(eps_p):
    return 105.0 + 1392.0 * np.power(np.clip(eps_p, 0.0, None), 0.642)


def upsetting_deck(mu: float, nr: int = 12, nz: int = 14, increments: int = 50) -> str:
    nodes, n = [], 1
    spec = {}
    for j in range(nz + 1):
        for i in range(nr + 1):
            spec[i, j] = n
            nodes.append(f"{n},{R0 * i / nr:.9g},{H * j / nz:.9g}")
            n += 1
    npl, plat = 2 * nr + 6, {}
    for j in range(2):
        for i in range(npl + 1):
            plat[i, j] = n
            nodes.append(f"{n},{1.8 * R0 * i / npl:.9g},{H + 0.5 * j:.9g}")
            n += 1
    el, e, top, side, platen = [], 1, [], [], []
    for j in range(nz):
        for i in range(nr):
            el.append(f"{e},{spec[i, j]},{spec[i + 1, j]},{spec[i + 1, j + 1]},{spec[i, j + 1]}")
            top += [e] if j == nz - 1 else []
            side += [e] if i == nr - 1 else []
            e += 1
    pel = []
    for i in range(npl):
        pel.append(f"{e},{plat[i, 0]},{plat[i + 1, 0]},{plat[i + 1, 1]},{plat[i, 1]}")
        platen.append(e)
        e += 1
    eps_table = np.concatenate([[0.0], np.geomspace(1e-4, 1.5, 70)])
    lines = ["*HEADING", f"upsetting, mu={mu}", "*NODE", *nodes,
             "*ELEMENT,TYPE=CAX4R,ELSET=SPEC", *el, "*ELEMENT,TYPE=CAX4R,ELSET=PLAT", *pel,
             "*NSET,NSET=AXIS", *[str(spec[0, j]) for j in range(nz + 1)],
             "*NSET,NSET=BOT", *[str(spec[i, 0]) for i in range(nr + 1)],
             "*NSET,NSET=PLN", *[str(v) for v in plat.values()],
             "*NSET,NSET=SIDE", *[str(spec[nr, j]) for j in range(nz + 1)],
             "*NSET,NSET=TOPAX", str(spec[0, nz]),
             "*SURFACE,NAME=SSLAVE,TYPE=ELEMENT", *[f"{x},S3" for x in top], *[f"{x},S2" for x in side],
             "*SURFACE,NAME=SMASTER,TYPE=ELEMENT", *[f"{x},S1" for x in platen],
             "*MATERIAL,NAME=STEEL", "*ELASTIC", f"{E},0.3", "*PLASTIC",
             *[f"{flow(x):.6g},{x:.6g}" for x in eps_table],
             "*MATERIAL,NAME=CARBIDE", "*ELASTIC", "560000,0.22",
             "*SOLID SECTION,ELSET=SPEC,MATERIAL=STEEL", "*SOLID SECTION,ELSET=PLAT,MATERIAL=CARBIDE",
             "*SURFACE INTERACTION,NAME=SI", "*SURFACE BEHAVIOR,PRESSURE-OVERCLOSURE=LINEAR", "1.e8,1.0"]
    if mu > 0:  # μ = 0: no *FRICTION at all (CALCULIX.md)
        lines += ["*FRICTION", f"{mu},1.e7"]
    lines += ["*CONTACT PAIR,INTERACTION=SI,TYPE=SURFACE TO SURFACE", "SSLAVE,SMASTER",
              "*BOUNDARY", "AXIS,1,1,0.", "BOT,2,2,0.",
              "*STEP,NLGEOM,INC=1000", "*STATIC,DIRECT", f"{1 / increments},1.",
              "*BOUNDARY", "PLN,1,1,0.", f"PLN,2,2,{-DZ}", f"TOPAX,2,2,{-DZ}",
              "*NODE PRINT,NSET=PLN,TOTALS=ONLY", "RF", "*NODE PRINT,NSET=SIDE", "U", "*END STEP"]
    return "\n".join(lines) + "\n"


BLOCK = re.compile(
    r"total force \(fx,fy,fz\) for set PLN and time\s+(\S+)\s*\n\s*\n\s*\S+\s+(\S+)\s+\S+\s*\n\s*\n"
    r"\s*displacements.*?time\s+\S+\s*\n\s*\n((?:\s+\d+\s+\S+\s+\S+\s+\S+\n)+)")


def parse(dat: str):
    """time, full-ring force (N), largest side radius (mm) per increment."""
    t, f, r = [], [], []
    for m in BLOCK.finditer(dat):
        rows = np.array([[float(v) for v in line.split()] for line in m.group(3).strip().splitlines()])
        t.append(float(m.group(1)))
        f.append(-float(m.group(2)) * SECTOR)
        r.append(R0 + rows[:, 1].max())
    return np.array(t), np.array(f), np.array(r)


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    jobs = {}
    for mu in (0.0, 0.1):
        folder = tmp_path_factory.mktemp(f"ccx_mu{mu:g}")
        (folder / "up.inp").write_text(upsetting_deck(mu))
        env = {**os.environ, "OMP_NUM_THREADS": "1"}
        jobs[mu] = (folder, subprocess.Popen(["ccx", "-i", "up"], cwd=folder, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True))
    out = {}
    for mu, (folder, proc) in jobs.items():
        log, _ = proc.communicate(timeout=300)
        assert proc.returncode == 0 and "*ERROR" not in log, log[-2000:]
        t, f, r = parse((folder / "up.dat").read_text())
        assert t.size and t[-1] == pytest.approx(1.0), "the run did not reach the end of the step"
        out[mu] = (t, f, r)
    return out


def _state(t):
    h = 2 * (H - DZ * t)  # full height
    eps = np.log(2 * H / h)
    r_n = R0 * np.sqrt(2 * H / h)
    return h, eps, r_n


def test_frictionless_run_matches_the_flow_curve(runs):
    t, f, _ = runs[0.0]
    h, eps, r_n = _state(t)
    p = f / (math.pi * r_n**2)
    ratio = p / flow(eps - p / E)
    sel = eps > 0.05
    assert np.all(np.abs(ratio[sel] - 1) < 0.015), ratio[sel]  # the mesh's own deficit (~0.9 %)


def test_slab_and_siebel_factors_against_calculix(runs, capsys):
    t0, f0, _ = runs[0.0]
    t1, f1, r1 = runs[0.1]
    assert np.allclose(t0, t1)
    h, eps, r_n = _state(t1)
    fe_factor = f1 / f0  # p/σ_f with the mesh deficit divided out
    slab = fr.slab_factor(0.1, r_n, h)
    siebel = fr.siebel_factor(0.1, r_n, h)
    ks = fr.k_sigma(0.1, eps)
    sel = eps > 0.05
    with capsys.disabled():
        print("\n  CalculiX mu=0.1:  eps   FE p/sf   slab    Siebel   K_sigma     FE dR/h   (3.18) dR/h")
        for i in np.nonzero(sel)[0][::8].tolist() + [len(t1) - 1]:
            print(f"                 {eps[i]:.3f}  {fe_factor[i]:.4f}  {slab[i]:.4f}  {siebel[i]:.4f}  {ks[i]:.4f}"
                  f"    {(r1[i] - r_n[i]) / h[i]:.4f}    {float(fr.bulge_ratio(eps[i], 0.1)):.4f}")
        mu_319 = fr.friction_bulge_regression(2 * R0, 2 * H, h[-1], d_max_mm=2 * r1[-1]).mu
        print(f"  mu from the CalculiX barrel by (3.19): {mu_319:.3f} (run with 0.100)")
    # the corrections remove the friction effect to within 1 % of the flow stress
    assert np.all(np.abs(fe_factor[sel] / slab[sel] - 1) < 0.01)
    assert np.all(np.abs(fe_factor[sel] / siebel[sel] - 1) < 0.01)
    # friction raises the mean pressure, and more as the specimen flattens
    assert np.all(fe_factor[sel] > 1.0) and fe_factor[-1] > fe_factor[np.argmax(sel)]
    # the barrel grows with strain
    bulge = (r1 - r_n) / h
    assert bulge[-1] > bulge[np.argmax(sel)] > 0
