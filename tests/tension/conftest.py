"""A synthetic tension record made from a known law, frame stiffness, toe and fracture."""

import math

import numpy as np
import pandas as pd
import pytest

from flowcurve.record.format import Record
from flowcurve.identification.laws.hardening import johnson_cook_static
from flowcurve.identification.tension.necking import davidenkov_factor, le_roy_a_over_R

TRUTH = dict(E_MPa=200_000.0, A=400.0, B=600.0, n=0.3, C_N_per_um=136.0, slack_mm=0.08, slack_force_N=600.0,
             d0_mm=6.0, l0_mm=30.0, eps_f=0.8)


def make_record(truth=TRUTH, *, extensometer=True, noise_N=0.0, seed=0):
    """Constant-volume tension of a Johnson-Cook material, recorded through a compliant frame.

    force from the law; crosshead = specimen elongation + P/C + slack (taken up below
    slack_force_N); extensometer = the specimen elongation on l0. After the Considère point the
    force falls linearly to the fracture force that, with the Davidenkov correction and Le Roy's
    a/R, gives back the law's stress at eps_f.
    """
    E, A, B, n = truth["E_MPa"], truth["A"], truth["B"], truth["n"]
    s0 = math.pi * truth["d0_mm"] ** 2 / 4
    l0 = truth["l0_mm"]
    sig_el = np.linspace(0.0, A, 150, endpoint=False)
    eps_pl = np.linspace(0.0, 0.35, 700)
    sig_t = np.concatenate([sig_el, johnson_cook_static(eps_pl, A, B, n)])
    eps_p = np.concatenate([np.zeros_like(sig_el), eps_pl])
    eps = eps_p + sig_t / E
    e = np.expm1(eps)
    force = sig_t * s0 / (1 + e)  # constant volume: S = S0/(1 + e)
    i_m = int(np.argmax(force))
    force, e = force[: i_m + 1], e[: i_m + 1]
    eps_u = math.log1p(e[-1])
    # necking: force falls to the fracture force over 100 samples
    eps_f = truth["eps_f"]
    sk = s0 * math.exp(-eps_f)
    eta = float(davidenkov_factor(le_roy_a_over_R(eps_f, eps_u)))
    Pk = float(johnson_cook_static(eps_f, A, B, n)) * sk / eta
    tail_F = np.linspace(force[-1], Pk, 101)[1:]
    tail_e = e[-1] + np.linspace(0, 0.06, 101)[1:]
    force, e = np.concatenate([force, tail_F]), np.concatenate([e, tail_e])
    rng = np.random.default_rng(seed)
    force_rec = force + rng.normal(0, noise_N, force.size) if noise_N else force
    spec_mm = e * l0
    P = np.clip(force, 0, None)
    slack = truth["slack_mm"] * (1 - np.clip(1 - P / truth["slack_force_N"], 0, 1) ** 2)
    cross = spec_mm + P / (truth["C_N_per_um"] * 1000) + slack
    data = {"time_s": np.arange(force.size) * 0.1, "force_N": force_rec, "crosshead_mm": cross}
    if extensometer:
        data["extensometer_mm"] = spec_mm
    meta = {"test": "tension", "material": "synthetic JC", "specimen.d0_mm": repr(truth["d0_mm"]),
            "specimen.l0_mm": repr(l0), "specimen.extensometer_gauge_mm": repr(l0),
            "post.dk_mm": repr(math.sqrt(4 * sk / math.pi)), "crosshead_speed_mm_per_s": "0.01"}
    info = {"s0_mm2": s0, "eps_u": eps_u, "Fm_N": float(force[i_m]), "e_m": float(e[i_m]), "Pk_N": Pk}
    return Record(meta=meta, data=pd.DataFrame(data), source="synthetic.csv"), info


@pytest.fixture
def synthetic():
    return make_record
