"""Records made from CalculiX runs: the test the rig would have recorded.

Compression (:func:`upsetting_record`):
The FE force–stroke history of a known flow curve and Coulomb μ becomes a record with the
rig's artefacts: the crosshead at constant speed (so the elastic line takes the time the frame's
compliance gives it), a seating toe (a soft contact in series that closes ``toe_mm`` as the force
reaches ``toe_force_N``), the frame compliance (crosshead = specimen + toe + F/C), 10 µm encoder
steps, force noise and an elastic unloading branch. The post-test measurements are taken
after elastic spring-back: hk = h·(1 + σ/E), dmax = d_max·(1 − ν·σ/E) with σ = F/A at the end
(the unloading run itself can fail with friction, docs/calculix.md; the spring-back moves hk by
~0.01 mm and dmax by a few µm).
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from flowcurve.record.format import Record
from flowcurve.record.specimen import circle_area_mm2
from flowcurve.identification.fe.model.upsetting import UpsettingResult
from flowcurve.identification.fe.model.tension import TensionModel, TensionResult


def upsetting_record(run: UpsettingResult, *, stiffness_N_per_um: float = 136.0, toe_mm: float = 0.03, toe_force_N: float = 300.0,
                     noise_N: float = 30.0, step_mm: float = 0.01, speed_mm_per_s: float = 0.01, rate_hz: float = 5.0,
                     seed: int = 1, material: str = "FE record", specimen_id: str = "fe-1", end_face: bool = False) -> Record:
    """A compression :class:`Record` of ``run`` (compression negative, as the rig gives it);
    with ``end_face`` the post-test measurements include the original end face's diameter."""
    m = run.model
    rng = np.random.default_rng(seed)
    stroke = np.concatenate([[0.0], run.stroke_mm])
    force = np.concatenate([[0.0], run.force_N])
    compliance = 1.0 / (stiffness_N_per_um * 1000.0)  # mm/N
    # the crosshead, not the specimen, moves at the set speed: on a fine path of the specimen's
    # stroke, crosshead = specimen + toe + F/C, with the seating toe a soft contact in series that
    # closes (toe_mm) as the force reaches toe_force_N: toe = toe_mm·√(F/F_toe)
    path = np.unique(np.concatenate([stroke, np.linspace(0.0, stroke[-1], 20001)]))
    f_path = np.interp(path, stroke, force)
    toe_path = toe_mm * np.sqrt(np.clip(f_path / toe_force_N, 0.0, 1.0)) if toe_mm > 0 else np.zeros_like(path)
    cross_path = np.maximum.accumulate(path + toe_path + f_path * compliance)
    t_load = np.arange(0.0, cross_path[-1] / speed_mm_per_s, 1.0 / rate_hz)
    s = np.interp(t_load * speed_mm_per_s, cross_path, path)
    f = np.interp(s, stroke, force)
    # elastic unloading in 20 s
    area = math.pi * m.d0_mm**2 * m.h0_mm / (4.0 * run.height_mm[-1])
    sigma_end = run.force_N[-1] / area
    frac = 1.0 - np.arange(1, int(20 * rate_hz) + 1) / (20 * rate_hz)
    f_un = run.force_N[-1] * frac
    s_un = stroke[-1] - run.height_mm[-1] * sigma_end / m.E_MPa * (1.0 - frac)
    F = np.concatenate([f, f_un])
    spec = np.concatenate([s, s_un])
    toe = np.concatenate([toe_mm * np.sqrt(np.clip(f / toe_force_N, 0.0, 1.0)) if toe_mm > 0 else np.zeros_like(f), np.full(f_un.size, toe_mm)])
    time = np.arange(F.size) / rate_hz
    cross = spec + toe + F * compliance
    cross = np.round(cross / step_mm) * step_mm
    F_meas = F + rng.normal(0.0, noise_N, F.size)
    hk = run.height_mm[-1] * (1.0 + sigma_end / m.E_MPa)
    dmax = run.dmax_mm[-1] * (1.0 - m.nu * sigma_end / m.E_MPa)
    meta = {
        "test": "compression", "material": material, "specimen.id": specimen_id, "nominal_temperature_C": "20",
        "crosshead_speed_mm_per_s": repr(speed_mm_per_s), "rig.frame_stiffness_N_per_um": repr(stiffness_N_per_um),
        "specimen.d0_mm": repr(m.d0_mm), "specimen.h0_mm": repr(m.h0_mm), "material.E_MPa": repr(m.E_MPa),
        "post.hk_mm": f"{hk:.4f}", "post.dmax_mm": f"{dmax:.4f}",
        "fe.mu": repr(m.mu),  # the truth the record was made with
    }
    if end_face:  # the top rim node's diameter, sprung back like dmax
        meta["post.dface_mm"] = f"{run.dtop_mm[-1] * (1.0 - m.nu * sigma_end / m.E_MPa):.4f}"
    data = pd.DataFrame({"time_s": time, "force_N": -F_meas, "crosshead_mm": -cross})
    return Record(meta=meta, data=data, source=specimen_id)


def tension_case_model(flow, taper: float) -> TensionModel:
    """The model of the FE tension records (tests, benches): d0 6 × l0 30 pulled 8 mm, a finer mesh
    (10×40) and smaller increments (1/120) than the inverse's own (8×30, 1/100), a cosine taper of
    ``taper`` and a small first increment (:data:`RECORD_FIRST_INCREMENT`)."""
    return TensionModel.from_law(6.0, 30.0, 8.0, flow, nr=10, nz=40, imperfection=taper, increments=120,
                                 first_increment=RECORD_FIRST_INCREMENT)


def tension_record(run: TensionResult, *, stiffness_N_per_um: float = 40.0, noise_N: float = 10.0, step_mm: float = 0.001,
                   speed_mm_per_s: float = 0.02, rate_hz: float = 10.0, seed: int = 1, material: str = "FE record",
                   specimen_id: str = "fe-tension-1") -> Record:
    """A tension :class:`Record` of ``run`` broken at its last increment: the frame compliance
    (crosshead = elongation + F/C), 1 µm encoder steps, force noise, then the break (the force
    falls to noise). Post-test: dk = the FE neck diameter, lu = l0 + elongation less the elastic
    part F_k·l0/(S0·E) (the necked section springs back less; the difference is < 0.01 mm)."""
    m = run.model
    rng = np.random.default_rng(seed)
    elong = np.concatenate([[0.0], run.elongation_mm])
    force = np.concatenate([[0.0], run.force_N])
    t = np.arange(0.0, elong[-1] / speed_mm_per_s, 1.0 / rate_hz)
    e = np.interp(t * speed_mm_per_s, elong, elong)
    f = np.interp(e, elong, force)
    n_break = 5
    e = np.concatenate([e, e[-1] + speed_mm_per_s / rate_hz * np.arange(1, n_break + 1)])
    f = np.concatenate([f, np.zeros(n_break)])
    time = np.arange(e.size) / rate_hz
    cross = np.round((e + f / (stiffness_N_per_um * 1000.0)) / step_mm) * step_mm
    F_meas = f + rng.normal(0.0, noise_N, f.size)
    s0 = circle_area_mm2(m.d0_mm)
    lu = m.l0_mm + float(run.elongation_mm[-1]) - float(run.force_N[-1]) * m.l0_mm / (s0 * m.E_MPa)
    meta = {
        "test": "tension", "material": material, "specimen.id": specimen_id, "nominal_temperature_C": "20",
        "crosshead_speed_mm_per_s": repr(speed_mm_per_s), "rig.frame_stiffness_N_per_um": repr(stiffness_N_per_um),
        "specimen.d0_mm": repr(m.d0_mm), "specimen.l0_mm": repr(m.l0_mm), "material.E_MPa": repr(m.E_MPa),
        "post.lu_mm": f"{lu:.3f}", "post.dk_mm": f"{2.0 * float(run.neck_radius_mm[-1]):.3f}",
    }
    data = pd.DataFrame({"time_s": time, "force_N": F_meas, "crosshead_mm": cross})
    return Record(meta=meta, data=data, source=specimen_id)


def johnson_cook_flow(eps_p, A, B, n):
    """σ = A + B·ε_p^n (the strain part of (2.19))."""
    return A + B * np.power(np.clip(eps_p, 0.0, None), n)


def voce_flow(eps_p, s0, q, b):
    """σ = s0 + q·(1 − exp(−b·ε_p)) (saturating hardening)."""
    return s0 + q * (1.0 - np.exp(-b * np.clip(eps_p, 0.0, None)))


def swift_flow(eps_p, K, eps0, n):
    """σ = K·(ε0 + ε_p)^n."""
    return K * np.power(eps0 + np.clip(eps_p, 0.0, None), n)


# Upsetting cases the FE table did not train on: other μ, h0/d0, d0 and hardening laws
# (the table has Swift K 1000, ε0 0.002, n 0.05/0.2/0.4/0.65, d0 6, μ 0–0.35, h0/d0 0.6/1/1.6/2.5).
VALIDATION_CASES = (
    {"name": "seed 12Kh18N12M3TL, mu 0.12, h0/d0 1.5", "law": (johnson_cook_flow, {"A": 105.0, "B": 1392.0, "n": 0.642}), "mu": 0.12, "d0": 6.0, "h0": 9.0, "eps_end": 0.72, "E": 194_000.0},
    {"name": "12Kh18N10T, mu 0.05, h0/d0 1.25", "law": (johnson_cook_flow, {"A": 280.0, "B": 1215.0, "n": 0.43}), "mu": 0.05, "d0": 8.0, "h0": 10.0, "eps_end": 0.7, "E": 200_000.0},
    {"name": "steel 45, mu 0.25, h0/d0 1.0", "law": (johnson_cook_flow, {"A": 410.0, "B": 280.0, "n": 0.47}), "mu": 0.25, "d0": 6.0, "h0": 6.0, "eps_end": 0.7, "E": 210_000.0},
    {"name": "Voce, mu 0.17, h0/d0 1.8", "law": (voce_flow, {"s0": 300.0, "q": 400.0, "b": 5.0}), "mu": 0.17, "d0": 5.0, "h0": 9.0, "eps_end": 0.7, "E": 200_000.0},
    {"name": "Swift n 0.3, mu 0.08, h0/d0 2.0", "law": (swift_flow, {"K": 800.0, "eps0": 0.01, "n": 0.3}), "mu": 0.08, "d0": 6.0, "h0": 12.0, "eps_end": 0.7, "E": 200_000.0},
    # the 30-element mesh stops at ε 0.42 here (the side folds onto the platen, with 70 or 140 increments): the table's
    {"name": "seed law, mu 0.28, h0/d0 1.2", "law": (johnson_cook_flow, {"A": 105.0, "B": 1392.0, "n": 0.642}), "mu": 0.28, "d0": 6.0, "h0": 7.2, "eps_end": 0.7, "E": 194_000.0,
     "mesh": {"nr": 24, "layers": 2, "layer_fraction": 1.0 / 24.0}},
)


RECORD_MESH = {"nr": 30, "layers": 2, "layer_fraction": 1.0 / 30.0}


def case_flow(case: dict):
    """The flow stress function (εp → MPa) of a synthetic ``case``."""
    from functools import partial

    fn, kw = case["law"]
    return partial(fn, **kw)


# the records' first increment, of the step: their elastic line resolved (ccx grows it while it converges easily); a first
# increment of 1/increments stepped past yield — the tension records' first point at 0.067 mm against a yield at
# 0.045–0.054 mm, and the fast method read E 135–165 GPa for 200 (193–199 with this one)
RECORD_FIRST_INCREMENT = 1.0 / 3000
RECORD_INCREMENTS = (70, 80, 60)  # the first that runs to the end; the rest only where a run stops


def case_model(case: dict, increments: int = RECORD_INCREMENTS[0]):
    """The upsetting model of a synthetic ``case`` at ``increments``."""
    from flowcurve.identification.fe.model.upsetting import UpsettingModel

    # a finer mesh than the table's and the inverse's (30 core elements, a d0/30 rim layer), 70 increments
    # and a small first one (the elastic line and the yield resolved); the rows CalculiX realises as the law
    # (a specimen of this flow curve, not the solver's 0.2–0.5 % lower reading of it: realised_law)
    return UpsettingModel.from_law(case["d0"], case["h0"], case["h0"] * math.exp(-case["eps_end"]), case["mu"], case_flow(case),
                                   E_MPa=case["E"], increments=increments, first_increment=RECORD_FIRST_INCREMENT,
                                   **case.get("mesh", RECORD_MESH)).realising()


def run_case(case: dict):
    """The case's CalculiX run. Where the side folds onto the platen a run can stop ("too many
    cutbacks") at a strain that moves with the increment size (Voce: 70 increments stop at ε 0.56,
    60 and 80 run to 0.7), so a stopped run is tried with the other :data:`RECORD_INCREMENTS`;
    if none finishes, the furthest is a test the machine stopped there, if it got past ε 0.55 (the
    tests read ε_p 0.05–0.6)."""
    from flowcurve.identification.fe.model.upsetting import simulate_upsetting

    best = None
    for increments in RECORD_INCREMENTS:
        run = simulate_upsetting(case_model(case, increments), require_complete=False)
        if run.completed:
            return run
        if best is None or (run.strain.size and run.strain[-1] > best.strain[-1]):
            best = run
    if best.strain.size == 0 or best.strain[-1] < 0.55:
        from flowcurve.identification.fe.model.ccx import SolverError

        raise SolverError(f"{case['name']}: the run stopped at ε {best.strain[-1] if best.strain.size else 0:.3g} < 0.55 ({best.message})")
    return best
