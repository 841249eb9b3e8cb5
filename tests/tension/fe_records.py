"""CalculiX tension records as a lab's machine writes them (issue 29): the product's necking model
(:func:`flowcurve.identification.fe.synthetic.tension_case_model`, 10×40 CAX8R, 120 increments)
run on a known law, then recorded through the artefacts of a real frame — a hold at zero force
before the motion, frame compliance 136 N/µm, a toe 0.02·(1 − e^(−F/100 N)) mm, 1 µm encoder
counts, 15 N force noise, 10 Hz — and broken at the run's end.

    python -m tests.tension.fe_records voce tests/tension/data/fe-voce-hold.csv

writes the vendored record the default tests read (the run takes about a minute; cached after).
"""

from __future__ import annotations

import math
import sys
from functools import partial

import numpy as np
import pandas as pd

from flowcurve.identification.fe.synthetic import swift_flow, tension_case_model, voce_flow
from flowcurve.identification.fe.model.tension import simulate_tension
from flowcurve.record.format import Record, write_record

# law, its parameters, the record's taper (the cosine imperfection that places the neck)
LAWS = {
    "voce": (voce_flow, {"s0": 300.0, "q": 400.0, "b": 8.0}, 0.004),
    "swift": (swift_flow, {"K": 900.0, "eps0": 0.01, "n": 0.2}, 0.003),
}
FRAME_N_PER_UM, TOE_MM, TOE_FORCE_N, NOISE_N, COUNT_MM, RATE_HZ, SPEED_MM_PER_S = 136.0, 0.02, 100.0, 15.0, 0.001, 10.0, 0.02


def law(name: str):
    flow, params, _ = LAWS[name]
    return partial(flow, **params)


def fe_tension_record(name: str, *, hold_s: float = 3.0, seed: int = 1) -> Record:
    """The record of the CalculiX run of law ``name`` with the artefacts above."""
    flow, params, taper = LAWS[name]
    run = simulate_tension(tension_case_model(partial(flow, **params), taper))
    m = run.model
    elong = np.concatenate([[0.0], run.elongation_mm])
    force = np.concatenate([[0.0], run.force_N])
    dt = 1.0 / RATE_HZ
    t_move = np.arange(0.0, elong[-1] / SPEED_MM_PER_S, dt)
    e = np.interp(t_move * SPEED_MM_PER_S, elong, elong)
    f = np.interp(e, elong, force)
    n_hold, n_break = int(round(hold_s * RATE_HZ)), 5
    e = np.concatenate([np.zeros(n_hold), e, e[-1] + SPEED_MM_PER_S * dt * np.arange(1, n_break + 1)])
    f = np.concatenate([np.zeros(n_hold), f, np.zeros(n_break)])  # the hold, the motion, the break
    toe = TOE_MM * (1.0 - np.exp(-np.clip(f, 0.0, None) / TOE_FORCE_N))
    cross = np.round((e + f / (FRAME_N_PER_UM * 1000.0) + toe) / COUNT_MM) * COUNT_MM  # crosshead = elongation + F/C + toe, in counts
    measured = f + np.random.default_rng(seed).normal(0.0, NOISE_N, f.size)
    s0 = math.pi * m.d0_mm**2 / 4.0
    lu = m.l0_mm + float(run.elongation_mm[-1]) - float(run.force_N[-1]) * m.l0_mm / (s0 * m.E_MPa)
    meta = {"test": "tension", "material": f"CalculiX {name} {params}", "specimen.id": f"fe-{name}", "nominal_temperature_C": "20",
            "crosshead_speed_mm_per_s": repr(SPEED_MM_PER_S), "rig.frame_stiffness_N_per_um": repr(FRAME_N_PER_UM),
            "specimen.d0_mm": repr(m.d0_mm), "specimen.l0_mm": repr(m.l0_mm), "material.E_MPa": repr(m.E_MPa),
            "post.lu_mm": f"{lu:.3f}", "post.dk_mm": f"{2.0 * float(run.neck_radius_mm[-1]):.3f}",
            "fe.made_with": f"tests/tension/fe_records.py: tension_case_model taper {taper}, hold {hold_s:g} s, frame {FRAME_N_PER_UM:g} N/um, "
                            f"toe {TOE_MM:g}(1-exp(-F/{TOE_FORCE_N:g} N)) mm, noise {NOISE_N:g} N, counts {1000 * COUNT_MM:g} um, {RATE_HZ:g} Hz, seed {seed}"}
    data = pd.DataFrame({"time_s": np.arange(e.size) * dt, "force_N": np.round(measured, 2), "crosshead_mm": np.round(cross, 4)})
    return Record(meta=meta, data=data, source=f"fe-{name}")


if __name__ == "__main__":
    write_record(sys.argv[2], fe_tension_record(sys.argv[1]))
