"""CalculiX upsetting runs as an independent check of the friction corrections.

Half model (symmetry at mid-height) of a d0 = 6, h0 = 7 mm cylinder compressed to 4.2 mm,
the product's O-grid model (:mod:`flowcurve.identification.fe.model.upsetting`, docs/calculix.md
"Upsetting").

Two runs, μ = 0 and μ = 0.1 (~2 s each, side by side). The μ = 0 run measures the mesh's own
force deficit (p/σ_f below 1); the μ = 0.1 run divided by it is the friction factor p/σ_f
that the slab and Siebel corrections claim to remove.
"""

from __future__ import annotations

import math
import shutil

import numpy as np
import pytest

from flowcurve.identification.compression import friction as fr
from flowcurve.identification.fe.model.upsetting import UpsettingModel, simulate_upsetting

pytestmark = [pytest.mark.slow, pytest.mark.solver,
              pytest.mark.skipif(shutil.which("ccx") is None, reason="CalculiX (ccx) is not installed")]

R0, H, DZ, E = 3.0, 3.5, 1.4, 194_000.0  # half model: radius, half height, platen travel (mm), MPa


def flow(eps_p):
    return 105.0 + 1392.0 * np.power(np.clip(eps_p, 0.0, None), 0.642)


@pytest.fixture(scope="module")
def runs():
    """time, full-ring force (N), largest outer radius (mm) per increment for μ 0 and 0.1."""
    out = {}
    for mu in (0.0, 0.1):
        m = UpsettingModel.from_law(2 * R0, 2 * H, 2 * (H - DZ), mu, flow, E_MPa=E, nu=0.3, increments=50)
        r = simulate_upsetting(m)
        out[mu] = (r.time, r.force_N, r.dmax_mm / 2)
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
